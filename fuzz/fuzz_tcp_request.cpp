// libFuzzer target: the Modbus/TCP request path. The input is the byte stream
// a client sends on one connection. It goes through server::TcpConnection,
// the state machine the TCP server's event loops run for each socket (a bad
// MBAP header ends the connection), which hands every frame's unit
// id and PDU to ModbusService::handle and tells it at the end that the client
// left. The same stream is played against three services: open, a client
// outside --write-allow, and settings locked by an unlock code
// (fuzz_tls_roles plays it as Modbus/TCP Security clients). Besides "no
// crash" (ASan, UBSan) each request must keep the invariants of
// fuzz_common.hpp: nothing but an accepted settings write changes a setting,
// a read-only client gets no write accepted, locked settings change only with
// the code, nothing moves without an accepted write that commands motion, and
// every reply fits a frame; and every reply goes back as a valid MBAP frame
// with the request's transaction id (mbap_input.hpp).
#include <array>
#include <cstddef>
#include <cstdint>

#include "mbap_input.hpp"

namespace {

std::array<fuzz::Harness, 3>& services() {
  using fuzz::Harness;
  static std::array<Harness, 3> s{Harness(Harness::Access::open), Harness(Harness::Access::read_only),
                                  Harness(Harness::Access::locked)};
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) { return fuzz::initialize(services); }

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz::play_connection(data, size, services());
}
