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

void PlantEvents::take(const StatusEvents& ring, const homing::Settings& settings) {
  for (std::uint64_t seq = taken_ + 1; seq <= ring.written(); ++seq) {
    const StatusEvent* e = ring.find(seq);
    if (!e) {
      spdlog::error("mqtt: status event {} was overwritten before it was kept (more than {} in one look)", seq,
                    StatusEvents::kRing);
      continue;
    }
    const std::size_t axis = e->axis >= 0 ? static_cast<std::size_t>(e->axis) : 0;
    switch (e->kind) {
      case StatusEventKind::alarm_raised:
        keep({.time_ms = e->time_ms, .kind = persistence::EventKind::alarm_raised, .axis = e->axis,
              .code = static_cast<std::int32_t>(e->code),
              .text = homing::describe_alarm(axis, e->axis >= 0 ? e->alarm : homing::Alarm{e->code}, settings)});
        break;
      case StatusEventKind::alarms_reset:
        keep({.time_ms = e->time_ms, .kind = persistence::EventKind::alarms_reset, .text = "alarms reset"});
        break;
      case StatusEventKind::cycle_started:
        keep({.time_ms = e->time_ms, .kind = persistence::EventKind::cycle_started, .axes = e->axes,
              .text = "homing started"});
        break;
      case StatusEventKind::cycle_ended: {
        std::string text = fmt::format("homing done in {} ms", e->duration_ms);
        if (e->code != homing::AlarmCode::none)
          text = fmt::format("homing ended after {} ms with alarm {}: {}", e->duration_ms, homing::alarm_name(e->code),
                             homing::describe_alarm(axis, e->axis >= 0 ? e->alarm : homing::Alarm{e->code}, settings));
        keep({.time_ms = e->time_ms, .kind = persistence::EventKind::cycle_ended, .axis = e->axis,
              .code = static_cast<std::int32_t>(e->code), .duration_ms = e->duration_ms, .axes = e->axes,
              .text = std::move(text)});
        break;
      }
    }
  }
  taken_ = ring.written();
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
