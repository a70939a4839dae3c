// docs/registers.md and the alarm list of docs/troubleshooting.md, generated
// from the register table and the engine's alarm table.
#include "registers/exports_docs.hpp"

#include <fmt/format.h>

namespace registers {
namespace {

struct AlarmConfirm {
  homing::AlarmCode code;
  std::string_view how;
};

// How to confirm each alarm at the machine, with what the module shows. The
// name, text and what to check are the engine's (homing/alarms.hpp).
constexpr AlarmConfirm kAlarmConfirm[] = {
    {homing::AlarmCode::sensor_not_found,
     "`axis.<a>.alarm_value` is the travel searched; `homingctl get axis.<a>.sensor` reads 1 while you press the "
     "switch by hand (else wiring or `sensor_nc`); `homingctl trace <a>` shows the sensor never turning on"},
    {homing::AlarmCode::overrun_during_stop,
     "`axis.<a>.alarm_value` is how far past the trigger the sensor was seen released (about the cam's length); "
     "`homingctl trace <a>`: the sensor turns off again while the axis is still braking; `homingctl check` shows the "
     "stop distance against the cam's length"},
    {homing::AlarmCode::stop_distance_exceeded,
     "`axis.<a>.stop_distance` against `axis.<a>.max_stop_distance`; `homingctl check` shows the stop distance the "
     "settings imply"},
    {homing::AlarmCode::not_released,
     "`homingctl get axis.<a>.sensor` reads 1 with the carriage clear of the switch (a stuck or shorted switch, an NC "
     "switch with a broken wire, or `sensor_nc` wrong)"},
    {homing::AlarmCode::index_not_found,
     "`homingctl trace <a>` shows no index pulse after the release edge; turn the motor by hand and watch the index "
     "input"},
    {homing::AlarmCode::slave_sensor_missing,
     "`homingctl check` names the slave; `axis.<a>.mode` of the slave is not a switch or pushing mode"},
    {homing::AlarmCode::misalignment,
     "on the slave, `axis.<a>.alarm_side` names the side that carried the pair out (and whether it had found its "
     "switch), `axis.<a>.alarm_value` how far out of square it would have come and `axis.<a>.alarm_rack_at_start` how "
     "far out the cycle found it; press each gantry switch by hand and watch `axis.<a>.sensor` of both axes; "
     "`homingctl trace` of both axes"},
    {homing::AlarmCode::hard_limit,
     "`axis.<a>.sensor` reads 1: the axis stands on its home sensor, which `shared_limit` makes a hard limit"},
    {homing::AlarmCode::soft_limit,
     "`axis.<a>.position` at `axis.<a>.soft_limit_min` or `soft_limit_max`; compare the real position of the carriage "
     "with the one shown"},
    {homing::AlarmCode::aborted, "`homingctl history` shows the run aborted; the log names the client that wrote `cmd.abort`"},
    {homing::AlarmCode::emergency_stop, "`status.estop` reads 1 while the e-stop chain is open"},
    {homing::AlarmCode::drive_fault,
     "`status.interlocks` bit `drive_fault` while the drive reports it; the drive's own display"},
    {homing::AlarmCode::settings_fault, "`homingctl check` lists every fault and the setting it names"},
    {homing::AlarmCode::communication_lost,
     "`host.heartbeat` stops changing (read it twice, `global.watchdog_ms` apart); `status.interlocks` bit "
     "`communication_lost`"},
    {homing::AlarmCode::settings_lost,
     "the daemon's log at start says the database was damaged and what it could restore; `homingctl get` shows the "
     "defaults"},
    {homing::AlarmCode::reapproach_not_found,
     "`homingctl trace <a>`: the sensor does not turn on again during the re-approach"},
    {homing::AlarmCode::permit_withdrawn,
     "`host.homing_permit` (or the permit input) reads 0; `status.interlocks` bit `permit_missing`"},
    {homing::AlarmCode::encoder_fault, "the drive's encoder alarm; the axis's absolute position is not valid"},
    {homing::AlarmCode::stop_not_found,
     "`homingctl trace <a>`: the axis travelled `max_seek_travel` and the stall input never turned on; watch the "
     "drive's stall output while it pushes"},
    {homing::AlarmCode::stall_timeout,
     "`homingctl trace <a>`: the push lasted `stall_timeout_ms` without a stall; the drive's torque-limit display"},
    {homing::AlarmCode::stall_at_start,
     "the stall input reads on at rest, before the axis moves (the drive still in torque limit, or its output stuck)"},
    {homing::AlarmCode::drive_no_answer,
     "`axis.<a>.phase` showed `drive_homing` for `drive_home_timeout_s`; the drive's display shows whether it homed "
     "and whether it received the home request"},
    {homing::AlarmCode::drive_answered_at_once,
     "the home done input reads 1 before and right after the request: watch it while the drive starts homing"},
    {homing::AlarmCode::drive_reference_lost,
     "the home done input reads 0 while the axis is homed; the drive's alarm history"},
    {homing::AlarmCode::unlock_not_confirmed,
     "`axis.<a>.phase` showed `unlock` for `lock_timeout_ms`; the unlock output is on and the unlocked input stays 0"},
    {homing::AlarmCode::lock_not_confirmed,
     "`axis.<a>.phase` showed `lock` for `lock_timeout_ms`; the unlocked input stays 1 after the unlock output went "
     "off"},
    {homing::AlarmCode::lock_engaged,
     "`axis.<a>.alarm_phase` is the phase the axis moved in; the unlocked input went to 0 during the motion"},
    {homing::AlarmCode::cam_not_found,
     "`axis.<a>.alarm_phase` is `limit_reversal` (the search back from the first limit switch) and "
     "`axis.<a>.alarm_value` the position where it met the other: the axis met both limit switches and "
     "`axis.<a>.sensor` never went to 1 on the way; move the carriage onto the cam by hand and watch "
     "`axis.<a>.sensor`"},
    {homing::AlarmCode::limit_in_homing,
     "`axis.<a>.alarm_phase` names the phase that ran into the limit switch (not `cam_seek`); "
     "`axis.<a>.alarm_value` is where it stood"},
    {homing::AlarmCode::both_limits_active,
     "with the carriage between the ends, both limit inputs read active (`axis.<a>.limit_min` and "
     "`axis.<a>.limit_max`, the `limits` column of `homingctl status`); on NC switches, a wire is open"},
    {homing::AlarmCode::limit_switch,
     "`axis.<a>.alarm_phase` is `jog`, `move` or `idle`; `axis.<a>.alarm_rule` names the end (1 negative, 2 "
     "positive), whose input (`axis.<a>.limit_min` or `limit_max`) reads active while the carriage stands on it, and "
     "`axis.<a>.alarm_value` is the position where it tripped"},
    {homing::AlarmCode::switch_not_repeatable,
     "`axis.<a>.latch_spread` (the figure in `axis.<a>.alarm_value`) is above `axis.<a>.max_latch_spread` over "
     "`axis.<a>.latch_passes_done` passes; home again and watch the spread and `axis.<a>.latch_sigma`"},
    {homing::AlarmCode::encoder_reversed,
     "`axis.<a>.alarm_phase` is `push_to_stop` and `axis.<a>.alarm_value` how far the encoder counted back; jog the "
     "axis and watch the encoder's (or the drive's) position display: it counts opposite to `axis.<a>.position`"},
    {homing::AlarmCode::travel_end_not_found,
     "`axis.<a>.alarm_phase` is `measure_travel` and `axis.<a>.alarm_value` the distance travelled from the home "
     "(max_seek_travel); jog the axis onto the far limit switch and watch its input (`homingctl status`), or on a "
     "hard-stop axis the drive's stall output as the carriage meets the stop"},
};

std::string registers_reference() {
  const std::string maps = export_markdown();
  // The maps' title and generated note are replaced by the docs' own.
  const auto note_end = maps.find("-->\n\n");
  const std::string body = note_end == std::string::npos ? maps : maps.substr(note_end + 5);
  return fmt::format(
      "# Register reference\n\n<!-- Generated by {} from registers/table.cpp; do not edit. -->\n\n"
      "Every register of the module and of the simulator unit, with its address, type, unit, scale, range and "
      "default, generated from the one register table (`registers/table.cpp`); a test fails when this file is "
      "stale (regenerate: `{}`). The same map is in `hmi_maps/registers.md` and, for programs, "
      "`hmi_maps/registers.csv`. How to use these registers from an HMI or a PLC: "
      "[hmi-integration.md](hmi-integration.md).\n\n{}",
      kDocsCommand, kDocsCommand, body);
}

std::string alarm_list() {
  std::string out = fmt::format(
      "Generated from the engine's alarm table (`homing/alarms.hpp`, the same as `hmi_maps/alarms.csv`) and the "
      "confirmation lines of `registers/exports_docs.cpp` by `{}`; a test fails when this list is stale. `<a>` is the "
      "axis the alarm names (`axis.<a>.alarm`).\n",
      kDocsCommand);
  for (const homing::AlarmInfo& a : homing::kAlarmInfo) {
    if (a.value == homing::AlarmCode::none) continue;
    out += fmt::format("\n### {} `{}`\n\n- **What happened:** {}.\n- **How to confirm:** {}.\n- **What to check:** {}.\n",
                       static_cast<int>(a.value), a.name, a.text, alarm_how_to_confirm(a.value), a.what_to_check);
  }
  return out;
}

}  // namespace

std::string_view alarm_how_to_confirm(homing::AlarmCode code) {
  for (const AlarmConfirm& c : kAlarmConfirm)
    if (c.code == code) return c.how;
  return "";
}

std::vector<GeneratedFile> generate_doc_files() { return {{"registers.md", registers_reference()}}; }

std::vector<GeneratedSection> generate_doc_sections() { return {{"troubleshooting.md", "alarms", alarm_list()}}; }

std::string begin_marker(std::string_view name) {
  return fmt::format("<!-- generated: {} ({}); do not edit until the end marker -->", name, kDocsCommand);
}

std::string end_marker(std::string_view name) { return fmt::format("<!-- end of generated: {} -->", name); }

std::optional<std::string> splice_section(const std::string& document, const GeneratedSection& section) {
  const std::string begin = begin_marker(section.name) + "\n";
  const std::string end = end_marker(section.name);
  const auto b = document.find(begin);
  if (b == std::string::npos) return std::nullopt;
  const auto e = document.find(end, b + begin.size());
  if (e == std::string::npos) return std::nullopt;
  return document.substr(0, b + begin.size()) + section.content + "\n" + document.substr(e);
}

}  // namespace registers
