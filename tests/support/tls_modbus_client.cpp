#include "tests/support/tls_modbus_client.hpp"

#include <stdexcept>

#include "registers/codec.hpp"
#include "tests/support/named_registers.hpp"
#include "tls/context.hpp"

namespace test_support {
namespace {

std::uint8_t unit_of(const registers::Register& r) { return r.unit == registers::Unit::module ? 1 : 247; }

void put16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v & 0xFF));
}

std::uint8_t read_function(registers::Table t) {
  switch (t) {
    case registers::Table::coil: return 1;
    case registers::Table::discrete_input: return 2;
    case registers::Table::input_register: return 4;
    case registers::Table::holding_register: return 3;
  }
  return 3;
}

}  // namespace

std::expected<TlsModbusClient, std::string> TlsModbusClient::connect(int port, const TlsIdentity& identity,
                                                                     std::chrono::milliseconds timeout) {
  auto ctx = tls::client_context(tls::ClientFiles{identity.cert, identity.key, identity.ca});
  if (!ctx) return std::unexpected(ctx.error());
  return connect(port, std::move(*ctx), timeout);
}

std::expected<TlsModbusClient, std::string> TlsModbusClient::connect(int port, tls::SslCtx ctx,
                                                                     std::chrono::milliseconds timeout) {
  auto client = tls::Client::connect("127.0.0.1", port, ctx.get(), timeout);
  if (!client) return std::unexpected(client.error());
  return TlsModbusClient(std::move(ctx), std::move(*client));
}

std::expected<std::vector<std::uint8_t>, std::string> TlsModbusClient::transaction(std::uint8_t unit,
                                                                                   std::span<const std::uint8_t> pdu,
                                                                                   std::chrono::milliseconds timeout) {
  const auto deadline = tls::Client::Clock::now() + timeout;
  const std::uint16_t tid = transaction_id_++;
  std::vector<std::uint8_t> frame;
  put16(frame, tid);
  put16(frame, 0);
  put16(frame, static_cast<std::uint16_t>(pdu.size() + 1));
  frame.push_back(unit);
  frame.insert(frame.end(), pdu.begin(), pdu.end());
  if (auto sent = client_.write_all(frame, deadline); !sent) return std::unexpected(sent.error());
  std::uint8_t header[7];
  if (auto got = client_.read_exact(header, deadline); !got) return std::unexpected(got.error());
  const std::size_t length = (std::size_t{header[4]} << 8) | header[5];
  if (((header[0] << 8) | header[1]) != tid || header[2] != 0 || header[3] != 0 || length < 2 || header[6] != unit)
    return std::unexpected("a reply that does not frame this request");
  std::vector<std::uint8_t> reply(length - 1);
  if (auto got = client_.read_exact(reply, deadline); !got) return std::unexpected(got.error());
  return reply;
}

std::expected<std::vector<std::pair<std::uint16_t, std::vector<std::uint8_t>>>, std::string> TlsModbusClient::pipeline(
    std::uint8_t unit, const std::vector<std::vector<std::uint8_t>>& pdus, bool one_record,
    std::chrono::milliseconds timeout) {
  const auto deadline = tls::Client::Clock::now() + timeout;
  std::vector<std::uint8_t> all;
  for (const auto& pdu : pdus) {
    std::vector<std::uint8_t> frame;
    put16(frame, transaction_id_++);
    put16(frame, 0);
    put16(frame, static_cast<std::uint16_t>(pdu.size() + 1));
    frame.push_back(unit);
    frame.insert(frame.end(), pdu.begin(), pdu.end());
    if (one_record) {
      all.insert(all.end(), frame.begin(), frame.end());
    } else if (auto sent = client_.write_all(frame, deadline); !sent) {
      return std::unexpected(sent.error());
    }
  }
  if (one_record)
    if (auto sent = client_.write_all(all, deadline); !sent) return std::unexpected(sent.error());
  std::vector<std::pair<std::uint16_t, std::vector<std::uint8_t>>> replies;
  for (std::size_t i = 0; i < pdus.size(); ++i) {
    std::uint8_t header[7];
    if (auto got = client_.read_exact(header, deadline); !got)
      return std::unexpected("reply " + std::to_string(i + 1) + ": " + got.error());
    const std::size_t length = (std::size_t{header[4]} << 8) | header[5];
    if (length < 2) return std::unexpected("a reply that does not frame a request");
    std::vector<std::uint8_t> reply(length - 1);
    if (auto got = client_.read_exact(reply, deadline); !got) return std::unexpected(got.error());
    replies.emplace_back(static_cast<std::uint16_t>((header[0] << 8) | header[1]), std::move(reply));
  }
  return replies;
}

std::int64_t TlsModbusClient::read(std::string_view name) {
  const registers::Register& r = reg(name);
  std::vector<std::uint8_t> pdu{read_function(r.table)};
  put16(pdu, r.address);
  put16(pdu, r.words());
  auto reply = transaction(unit_of(r), pdu);
  if (!reply) throw std::runtime_error("reading " + std::string(name) + ": " + reply.error());
  if (reply->size() < 2 || ((*reply)[0] & 0x80))
    throw std::runtime_error("reading " + std::string(name) + ": exception " +
                             std::to_string(reply->size() >= 2 ? (*reply)[1] : -1));
  if (r.table == registers::Table::coil || r.table == registers::Table::discrete_input) return (*reply)[2] & 1;
  std::uint16_t words[2] = {0, 0};
  for (std::size_t i = 0; i < r.words(); ++i)
    words[i] = static_cast<std::uint16_t>(((*reply)[2 + 2 * i] << 8) | (*reply)[3 + 2 * i]);
  return registers::decode_words(r, std::span<const std::uint16_t>(words, r.words()), registers::WordOrder::high_first);
}

int TlsModbusClient::write(std::string_view name, std::int64_t raw) {
  const registers::Register& r = reg(name);
  std::vector<std::uint8_t> pdu;
  if (r.table == registers::Table::coil) {
    pdu = {5};
    put16(pdu, r.address);
    put16(pdu, raw ? 0xFF00 : 0x0000);
  } else {
    std::uint16_t words[2] = {0, 0};
    registers::encode_words(r, raw, registers::WordOrder::high_first, std::span<std::uint16_t>(words, r.words()));
    pdu = {16};
    put16(pdu, r.address);
    put16(pdu, r.words());
    pdu.push_back(static_cast<std::uint8_t>(2 * r.words()));
    for (std::size_t i = 0; i < r.words(); ++i) put16(pdu, words[i]);
  }
  auto reply = transaction(unit_of(r), pdu);
  if (!reply) {
    last_error_ = reply.error();
    return -1;
  }
  if (reply->size() >= 2 && ((*reply)[0] & 0x80)) return (*reply)[1];
  return 0;
}

}  // namespace test_support
