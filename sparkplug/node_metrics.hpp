#pragma once
// The metrics of the Sparkplug B edge node, derived from the one register
// table: every input register and discrete input of the module unit becomes
// one metric (name from the register's name, datatype from its type and
// quantity, alias from its place in the table). No second list of metrics.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "registers/table.hpp"

namespace sparkplug {

// Values of the specification's DataType enum that the module uses
// (sparkplug_b.proto holds the whole enum).
enum class DataType : std::uint32_t {
  int16 = 2, int32 = 3, int64 = 4, uint16 = 6, uint32 = 7, dbl = 10, boolean = 11, string = 12,
};

struct MetricDef {
  std::string name;   // "axis/X/position": the register name, folders by '/'
  std::uint64_t alias = 0;  // 1.. in table order (bdSeq and Node Control/Rebirth go by name)
  DataType type = DataType::uint16;
  const registers::Register* reg = nullptr;
};

inline constexpr std::string_view kBdSeqName = "bdSeq";
inline constexpr std::string_view kRebirthName = "Node Control/Rebirth";

// The register's name as a Sparkplug metric name.
std::string metric_name(const registers::Register& reg);
// Datatype on the wire: a scaled quantity (lengths, velocities) is sent in
// engineering units as Double, every other register as its raw integer type.
DataType data_type(const registers::Register& reg);
// Loop timing and resource figures: they move all the time, so they are
// published at most every ReportPolicy::diagnostics_min_interval_ms.
bool is_diagnostic(const registers::Register& reg);
// Every metric of the node (status.heartbeat excepted), in table order, aliases 1..n.
std::vector<MetricDef> node_metrics();

}  // namespace sparkplug
