#include "plant_events.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "homing/alarms.hpp"

namespace server {

PlantEvents::PlantEvents(persistence::EventOutbox& outbox, persistence::SettingsStore* store)
    : outbox_(outbox), store_(store) {
  // A new outbox starts at the present: the settings history before it is in
  // the audit log, not owed to the broker.
  if (store_ && !outbox_.audit_cursor())
    if (auto last = store_->last_change_id(); last)
      if (auto s = outbox_.set_audit_cursor(*last); !s) spdlog::error("mqtt: event outbox: {}", s.error().message);
}

void PlantEvents::keep(persistence::Event event, std::optional<std::int64_t> audit_id) {
  if (auto r = outbox_.push(std::move(event), audit_id); !r)
    spdlog::error("mqtt: an event could not be kept for the broker ({}): {}", outbox_.path(), r.error().message);
}

void PlantEvents::observe(const homing::Status& before, const homing::Status& now, const homing::Settings& settings,
                          std::int64_t now_ms) {
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const homing::Alarm& alarm = now.axes[a].alarm;
    if (alarm && alarm.code != before.axes[a].alarm.code)
      keep({.time_ms = now_ms, .kind = persistence::EventKind::alarm_raised, .axis = static_cast<std::int32_t>(a),
            .code = static_cast<std::int32_t>(alarm.code), .text = homing::describe_alarm(a, alarm, settings)});
  }
  if (now.global_alarm != homing::AlarmCode::none && now.global_alarm != before.global_alarm)
    keep({.time_ms = now_ms, .kind = persistence::EventKind::alarm_raised,
          .code = static_cast<std::int32_t>(now.global_alarm),
          .text = homing::describe_alarm(0, homing::Alarm{now.global_alarm}, settings)});
  if (before.alarm && !now.alarm)
    keep({.time_ms = now_ms, .kind = persistence::EventKind::alarms_reset, .text = "alarms reset"});
  if (now.homing && !before.homing) {
    std::int32_t axes = 0;
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (now.axes[a].busy) axes |= homing::axis_bit(a);
    keep({.time_ms = now_ms, .kind = persistence::EventKind::cycle_started, .axes = axes, .text = "homing started"});
  }
}

void PlantEvents::cycle_ended(const persistence::HomingRun& run, const homing::Status& now,
                              const homing::Settings& settings) {
  const std::int64_t took = run.end_ms - run.start_ms;
  std::string text = fmt::format("homing done in {} ms", took);
  if (run.result != 0) {
    const auto code = static_cast<homing::AlarmCode>(run.result);
    if (run.alarm_axis >= 0)
      text = fmt::format("homing ended after {} ms with alarm {}: {}", took, homing::alarm_name(code),
                         homing::describe_alarm(static_cast<std::size_t>(run.alarm_axis),
                                                now.axes[static_cast<std::size_t>(run.alarm_axis)].alarm, settings));
    else
      text = fmt::format("homing ended after {} ms with alarm {}", took, homing::alarm_name(code));
  }
  keep({.time_ms = run.end_ms, .kind = persistence::EventKind::cycle_ended, .axis = run.alarm_axis,
        .code = run.result, .duration_ms = took, .axes = run.axes, .text = std::move(text)});
}

void PlantEvents::settings_changes() {
  if (!store_) return;
  const std::int64_t after = outbox_.audit_cursor().value_or(0);
  auto rows = store_->changes_after(after, 256);
  if (!rows) {
    spdlog::error("mqtt: settings changes not read for the broker: {}", rows.error().message);
    return;
  }
  for (const auto& c : *rows)
    keep({.time_ms = c.time_ms, .kind = persistence::EventKind::setting_changed, .name = c.name,
          .old_value = c.old_value, .new_value = c.new_value,
          .text = fmt::format("{} {} -> {} by {} {}", c.name, c.old_value, c.new_value, c.transport, c.client)},
         c.id);
}

}  // namespace server
