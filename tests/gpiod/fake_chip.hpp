#pragma once
// A fake GPIO chip behind the LineApi seam: chips and lines declared by the
// test, outputs recorded as edges with the fake time, inputs played as
// kernel events. Errors come from the same texts as the libgpiod one. A line
// requested with events has an eventfd that, like the kernel's line
// descriptor, is readable while it has events queued.
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "homing/gpiod/line_api.hpp"
#include "homing/gpiod/line_errors.hpp"

namespace fake {

using namespace homing::gpiod;

struct Write {
  std::string role;
  bool value;
  std::int64_t time_ns;
};

class Chip final : public LineApi {
 public:
  struct ChipDef {
    unsigned lines = 32;
    std::map<unsigned, std::string> names;
    std::map<unsigned, std::string> busy;  // offset -> consumer
    int open_errno = 0;                    // e.g. EACCES
    std::set<unsigned> no_events;          // lines that refuse an events request (no interrupt)
  };

  ~Chip() override {
    for (const Line& l : lines_)
      if (l.event_fd >= 0) close(l.event_fd);
  }

  std::int64_t now_ns = 0;  // stamped on every recorded write
  std::map<std::string, ChipDef> chips{{"gpiochip0", ChipDef{}}};

  std::expected<LineId, std::string> request_output(const LineSpec& spec, bool initial) override {
    auto id = request(spec, true);
    if (id) {
      lines_[*id].value = initial;
      writes.push_back({spec.role, initial, now_ns});
    }
    return id;
  }
  std::expected<LineId, std::string> request_input(const LineSpec& spec) override { return request(spec, false); }
  std::expected<LineId, std::string> request_input_events(const LineSpec& spec) override {
    return request(spec, false, true);
  }
  std::expected<void, std::string> set_value(LineId id, bool value) override {
    std::lock_guard lock(mutex_);
    Line& l = lines_.at(static_cast<std::size_t>(id));
    if (l.fail_writes) return std::unexpected(describe(l.spec) + ": write failed: Input/output error");
    if (l.value != value) writes.push_back({l.spec.role, value, now_ns});
    l.value = value;
    return {};
  }
  std::expected<bool, std::string> get_value(LineId id) override {
    std::lock_guard lock(mutex_);
    return lines_.at(static_cast<std::size_t>(id)).value;
  }
  std::expected<std::size_t, std::string> read_events(LineId id, std::span<LineEvent> out) override {
    std::lock_guard lock(mutex_);
    Line& l = lines_.at(static_cast<std::size_t>(id));
    auto& q = l.events;
    std::size_t n = 0;
    while (n < out.size() && !q.empty()) {
      out[n++] = q.front();
      q.pop_front();
    }
    if (q.empty() && l.event_fd >= 0) {
      std::uint64_t count = 0;
      [[maybe_unused]] const ssize_t r = ::read(l.event_fd, &count, sizeof count);  // no longer readable
    }
    return n;
  }
  int event_fd(LineId id) override {
    std::lock_guard lock(mutex_);
    return lines_.at(static_cast<std::size_t>(id)).event_fd;
  }

  // --- test side ---------------------------------------------------------
  // An input changes: the kernel queues an event stamped kernel_ts_ns (on
  // whatever clock the test plays the kernel's) and the level follows.
  void play(const std::string& role, std::int64_t kernel_ts_ns, bool level) {
    std::lock_guard lock(mutex_);
    Line& l = by_role(role);
    l.value = level;
    l.events.push_back(LineEvent{kernel_ts_ns, level});
    if (l.event_fd >= 0) {
      const std::uint64_t one = 1;
      [[maybe_unused]] const ssize_t w = ::write(l.event_fd, &one, sizeof one);
    }
  }
  // The line's descriptor is readable (an event is queued).
  bool event_pending(const std::string& role) {
    std::lock_guard lock(mutex_);
    return !by_role(role).events.empty();
  }
  bool has_events(const std::string& role) {
    std::lock_guard lock(mutex_);
    return by_role(role).event_fd >= 0;
  }
  // The level changes and the kernel's event is lost.
  void set_level_silently(const std::string& role, bool level) {
    std::lock_guard lock(mutex_);
    by_role(role).value = level;
  }
  bool value(const std::string& role) {
    std::lock_guard lock(mutex_);
    return by_role(role).value;
  }
  void fail_writes(const std::string& role) {
    std::lock_guard lock(mutex_);
    by_role(role).fail_writes = true;
  }
  std::vector<Write> writes_of(const std::string& role) const {
    std::vector<Write> out;
    for (const Write& w : writes)
      if (w.role == role) out.push_back(w);
    return out;
  }
  bool requested(const std::string& role) const {
    for (const Line& l : lines_)
      if (l.spec.role == role) return true;
    return false;
  }

  std::vector<Write> writes;

 private:
  struct Line {
    LineSpec spec;
    unsigned offset = 0;
    bool output = false;
    bool value = false;
    bool fail_writes = false;
    std::deque<LineEvent> events;
    int event_fd = -1;  // requested with events
  };

  Line& by_role(const std::string& role) {
    for (Line& l : lines_)
      if (l.spec.role == role) return l;
    throw std::logic_error("fake chip: no line requested as " + role);
  }

  std::expected<LineId, std::string> request(const LineSpec& spec, bool output, bool events = false) {
    std::string chip_name = spec.chip;
    unsigned offset = 0;
    if (chip_name.empty()) {
      const auto* name = std::get_if<std::string>(&spec.line);
      if (!name) return std::unexpected(errors::offset_needs_chip(spec));
      bool found = false;
      for (const auto& [c, def] : chips)
        for (const auto& [o, n] : def.names)
          if (!found && n == *name) chip_name = c, offset = o, found = true;
      if (!found) return std::unexpected(errors::no_name(spec));
    }
    auto it = chips.find(chip_name);
    if (it == chips.end()) return std::unexpected(errors::chip_open(spec, chip_name, ENOENT));
    const ChipDef& def = it->second;
    if (def.open_errno != 0) return std::unexpected(errors::chip_open(spec, chip_name, def.open_errno));
    if (!spec.chip.empty()) {
      if (const auto* o = std::get_if<unsigned>(&spec.line)) {
        if (*o >= def.lines) return std::unexpected(errors::no_offset(spec, def.lines));
        offset = *o;
      } else {
        bool found = false;
        for (const auto& [o, n] : def.names)
          if (n == std::get<std::string>(spec.line)) offset = o, found = true;
        if (!found) return std::unexpected(errors::no_name(spec));
      }
    }
    if (auto b = def.busy.find(offset); b != def.busy.end()) return std::unexpected(errors::busy(spec, b->second));
    if (events && def.no_events.contains(offset)) return std::unexpected(errors::request_failed(spec, EIO));
    for (const Line& l : lines_)
      if (l.spec.chip == chip_name && l.offset == offset) return std::unexpected(errors::busy(spec, "homingd"));
    Line l;
    l.spec = spec;
    l.spec.chip = chip_name;
    l.offset = offset;
    l.output = output;
    if (events) l.event_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    lines_.push_back(l);
    return static_cast<LineId>(lines_.size() - 1);
  }

  std::mutex mutex_;
  std::deque<Line> lines_;
};

}  // namespace fake
