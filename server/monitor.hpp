#pragma once
// Watches the published status from outside the control loop: logs alarms
// and command results, records each homing run in the history, refreshes
// the home-correction summary that the input registers show, and after each
// run judges the health trend of its axes (health_trend.hpp).
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <thread>

#include "control_loop.hpp"
#include "modbus_service.hpp"
#include "persistence/settings_store.hpp"
#include "plant_events.hpp"
#include "recurring_warning.hpp"

namespace server {

class Monitor {
 public:
  // The store is thread-safe on its own: the monitor's history, summary and
  // backups never hold the Modbus side's lock.
  Monitor(ControlLoop& loop, ModbusService& service, persistence::SettingsStore* store,
          std::function<std::uint32_t()> tcp_clients = {});
  ~Monitor();
  // Homing cycles, alarms and settings changes for the plant (MQTT); before start().
  void set_plant_events(PlantEvents* events) { events_ = events; }
  void start();
  void stop();
  // One look at the status (tests call it directly).
  void poll(std::int64_t now_ms);

 private:
  void refresh_summary();
  void judge_health(std::size_t axis, const homing::Settings& settings);
  void refresh_diagnostics();
  void housekeeping(std::int64_t now_ms);
  std::chrono::milliseconds until_next_look(std::int64_t now_ms) const;
  static constexpr std::int64_t kHousekeepingMs = 500;
  static constexpr std::int64_t kCarriagesMinGapMs = 200;
  // ended: the loop's event for the cycle's end (its result), if the ring still holds it.
  void record_unseen_cycle(const Snapshot& snap, const homing::Settings& settings);
  void record_run(const homing::Status& st, const StatusEvent* ended, const homing::Settings& settings,
                  std::int64_t now_ms);
  void log_alarms(const StatusEvents& events, const homing::Settings& settings);
  void report_refcheck(const homing::Status& st, const homing::Settings& settings);
  void report_measurements(const homing::Status& st, const homing::Settings& settings);
  void keep_sim_carriages(const Snapshot& snap, std::int64_t now_ms);

  ControlLoop& loop_;
  ModbusService& service_;
  persistence::SettingsStore* store_;
  std::function<std::uint32_t()> tcp_clients_;
  registers::StatusExtras extras_{};
  std::int64_t last_housekeeping_ms_ = 0;
  // The store's housekeeping, tried at every look: a full disk is one line a minute, not two a second.
  RecurringWarning backup_warning_{"settings backup not written", "settings backup written again"};
  RecurringWarning checkpoint_warning_{"settings database not checkpointed", "settings database checkpointed again"};
  RecurringWarning prune_warning_{"audit log not pruned", "audit log pruned again"};
  homing::Status last_{};
  bool first_ = true;
  std::int64_t run_start_ms_ = 0;
  homing::AxisMask run_axes_ = 0;
  std::uint64_t alarm_events_taken_ = 0;  // the last event whose alarm was logged
  std::uint64_t cycle_events_taken_ = 0;  // the last cycle_ended event whose axes joined run_axes_
  std::array<homing::Measurement, homing::kAxisCount> measured_at_start_{};  // figures as the cycle started
  PlantEvents* events_ = nullptr;
  bool sim_behind_logged_ = false;
  // The last snapshot looked at: its news (Snapshot::news), and whether the loop idled.
  std::uint64_t last_news_ = 0;
  bool last_quiet_ = false;
  // The simulator's carriages as last written to the store, and when.
  std::optional<std::array<double, homing::kAxisCount>> carriages_kept_;
  std::int64_t carriages_kept_ms_ = 0;
  std::optional<std::int64_t> carriages_due_ms_;  // at rest somewhere new, kept no sooner than this
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

std::int64_t unix_ms();

// What the history records of one axis of a finished run: its correction
// only when the cycle succeeded and the axis was homed when it started,
// otherwise why not; its health figures whenever it ended homed.
persistence::AxisRun axis_record(bool cycle_ok, const homing::AxisStatus& axis, std::int64_t duration_ms);

}  // namespace server
