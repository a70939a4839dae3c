#pragma once
// FC 20 (read file record): the homing traces, one file per axis (file number
// = axis + 1, records = the registers of server/trace.hpp's layout).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "pdu.hpp"
#include "request_decoder.hpp"

namespace server {

// The file of one axis (0 = X) as registers; asked at most once per axis.
using TraceFileOf = std::function<std::vector<std::uint16_t>(std::size_t axis)>;

// Each sub-request in turn: reference type 6, an axis's file and records it
// has, else 02; 03 once the answer would not fit one PDU.
Reply read_trace_records(const FileRecordRequest& request, const TraceFileOf& file_of);

}  // namespace server
