#include "file_record.hpp"

#include <array>
#include <optional>

#include "homing/axes.hpp"
#include "registers/errors.hpp"

namespace server {

Reply read_trace_records(const FileRecordRequest& request, const TraceFileOf& file_of) {
  constexpr auto fc = static_cast<std::uint8_t>(FunctionCode::read_file_record);
  constexpr std::uint16_t kMaxRecord = 9999;  // the spec's record numbers: 0..9999
  auto fail = [](registers::ExceptionCode code) { return exception_reply(fc, static_cast<std::uint8_t>(code)); };
  Reply reply{true, {fc, 0}};
  std::array<std::optional<std::vector<std::uint16_t>>, homing::kAxisCount> files;
  for (const FileRecordRef& ref : request.records) {
    if (ref.reference_type != 6 || ref.file < 1 || ref.file > homing::kAxisCount || ref.record > kMaxRecord ||
        ref.length < 1)
      return fail(registers::ExceptionCode::illegal_data_address);
    auto& words = files[ref.file - 1u];
    if (!words) words = file_of(ref.file - 1u);
    if (std::size_t{ref.record} + ref.length > words->size())
      return fail(registers::ExceptionCode::illegal_data_address);
    if (reply.pdu.size() + 2u + 2u * ref.length > kMaxPdu) return fail(registers::ExceptionCode::illegal_data_value);
    reply.pdu.push_back(static_cast<std::uint8_t>(1 + 2 * ref.length));
    reply.pdu.push_back(6);
    for (std::uint16_t i = 0; i < ref.length; ++i) put16(reply.pdu, (*words)[ref.record + i]);
  }
  reply.pdu[1] = static_cast<std::uint8_t>(reply.pdu.size() - 2);
  return reply;
}

}  // namespace server
