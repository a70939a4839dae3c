#include "sparkplug/node_metrics.hpp"

#include <algorithm>

#include "homing/alarms.hpp"

namespace sparkplug {

std::string metric_name(const registers::Register& reg) {
  std::string name = reg.name();
  std::ranges::replace(name, '.', '/');
  return name;
}

DataType data_type(const registers::Register& reg) {
  if (reg.scale() != 1.0) return DataType::dbl;
  switch (reg.type) {
    case registers::Type::boolean: return DataType::boolean;
    case registers::Type::i16: return DataType::int16;
    case registers::Type::u32: return DataType::uint32;
    case registers::Type::i32: return DataType::int32;
    case registers::Type::u16:
    case registers::Type::enumeration:
    case registers::Type::bitmask: return DataType::uint16;
  }
  return DataType::uint16;
}

std::vector<MetricDef> node_metrics() {
  std::vector<MetricDef> out;
  for (const auto& reg : registers::registers_of(registers::Unit::module)) {
    if (reg.table != registers::Table::input_register && reg.table != registers::Table::discrete_input) continue;
    // The heartbeat changes every control period: on MQTT the broker's
    // keep-alive and NDEATH tell a host the module is alive.
    if (reg.key == registers::Key::status_heartbeat) continue;
    out.push_back(MetricDef{metric_name(reg), out.size() + 1, data_type(reg), &reg});
  }
  return out;
}

std::vector<TextMetricDef> alarm_text_metrics(std::uint64_t first_alias) {
  std::vector<TextMetricDef> out;
  for (const auto& reg : registers::registers_of(registers::Unit::module)) {
    if (reg.key != registers::Key::axis_alarm && reg.key != registers::Key::status_global_alarm) continue;
    out.push_back(TextMetricDef{metric_name(reg) + "_text", first_alias + out.size(), &reg});
  }
  return out;
}

std::string alarm_text(const registers::Register& code, const registers::ModuleView& view) {
  if (code.key == registers::Key::status_global_alarm) {
    const homing::AlarmCode global = view.status.global_alarm;
    return global == homing::AlarmCode::none ? std::string{} : homing::describe_global_alarm(global, view.settings);
  }
  const auto axis = static_cast<std::size_t>(code.axis);
  const homing::Alarm& alarm = view.status.axes[axis].alarm;
  return alarm ? homing::describe_alarm(axis, alarm, view.settings) : std::string{};
}

bool is_diagnostic(const registers::Register& reg) {
  switch (reg.key) {
    case registers::Key::diag_loop_periods:
    case registers::Key::diag_late_p50_us:
    case registers::Key::diag_late_p99_us:
    case registers::Key::diag_late_p999_us:
    case registers::Key::diag_late_max_us:
    case registers::Key::diag_engine_step_ns:
    case registers::Key::diag_rss_kb:
    case registers::Key::diag_tcp_clients:
      return true;
    default:
      return false;
  }
}

}  // namespace sparkplug
