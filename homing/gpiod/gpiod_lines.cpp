#include "gpiod_lines.hpp"

#include "line_errors.hpp"

#include <gpiod.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <fmt/format.h>

namespace homing::gpiod {
namespace {

int request_flags(const LineSpec& s) {
  int flags = s.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
  switch (s.bias) {
    case Bias::as_is: break;
    case Bias::disable: flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_DISABLE; break;
    case Bias::pull_up: flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_UP; break;
    case Bias::pull_down: flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_DOWN; break;
  }
  return flags;
}

}  // namespace

void GpiodLines::ChipDeleter::operator()(gpiod_chip* chip) const { gpiod_chip_close(chip); }

GpiodLines::GpiodLines(std::string consumer) : consumer_(std::move(consumer)) {}

GpiodLines::~GpiodLines() {
  // Releasing returns outputs to the kernel; the backend has already driven
  // them to their safe values.
  for (Line& l : lines_) gpiod_line_release(l.handle);
  lines_.clear();
  chips_.clear();
}

std::expected<gpiod_chip*, std::string> GpiodLines::open_chip(const LineSpec& spec, const std::string& key) {
  for (const Chip& c : chips_)
    if (c.key == key) return c.handle.get();
  errno = 0;
  ChipPtr chip(gpiod_chip_open_lookup(key.c_str()));
  if (!chip)
    return std::unexpected(errors::chip_open(spec, key, errno ? errno : ENODEV));
  gpiod_chip* raw = chip.get();
  chips_.push_back(Chip{key, std::move(chip)});
  return raw;
}

std::expected<gpiod_line*, std::string> GpiodLines::find_line(const LineSpec& spec) {
  if (spec.chip.empty()) {
    // A bare line name: search every chip, then keep that chip open here.
    const auto* name = std::get_if<std::string>(&spec.line);
    if (!name) return std::unexpected(errors::offset_needs_chip(spec));
    errno = 0;
    gpiod_line* found = gpiod_line_find(name->c_str());
    if (!found) return std::unexpected(errors::no_name(spec));
    const std::string chip_name = gpiod_chip_name(gpiod_line_get_chip(found));
    const unsigned offset = gpiod_line_offset(found);
    gpiod_line_close_chip(found);
    LineSpec resolved = spec;
    resolved.chip = chip_name;
    resolved.line = offset;
    return find_line(resolved);
  }
  auto chip = open_chip(spec, spec.chip);
  if (!chip) return std::unexpected(chip.error());
  gpiod_line* line = nullptr;
  if (const auto* offset = std::get_if<unsigned>(&spec.line)) {
    const unsigned count = gpiod_chip_num_lines(*chip);
    if (*offset >= count) return std::unexpected(errors::no_offset(spec, count));
    line = gpiod_chip_get_line(*chip, *offset);
  } else {
    line = gpiod_chip_find_line(*chip, std::get<std::string>(spec.line).c_str());
    if (!line) return std::unexpected(errors::no_name(spec));
  }
  if (!line) return std::unexpected(errors::request_failed(spec, errno));
  return line;
}

std::expected<LineId, std::string> GpiodLines::request(const LineSpec& spec, Kind kind, bool initial) {
  auto line = find_line(spec);
  if (!line) return std::unexpected(line.error());
  if (gpiod_line_is_requested(*line) || gpiod_line_is_used(*line)) {
    const char* user = gpiod_line_consumer(*line);
    return std::unexpected(errors::busy(spec, user ? user : ""));
  }
  gpiod_line_request_config cfg{consumer_.c_str(), 0, request_flags(spec)};
  cfg.request_type = kind == Kind::output   ? GPIOD_LINE_REQUEST_DIRECTION_OUTPUT
                     : kind == Kind::input ? GPIOD_LINE_REQUEST_DIRECTION_INPUT
                                           : GPIOD_LINE_REQUEST_EVENT_BOTH_EDGES;
  errno = 0;
  if (gpiod_line_request(*line, &cfg, initial ? 1 : 0) != 0)
    return std::unexpected(errno == EBUSY ? errors::busy(spec, "") : errors::request_failed(spec, errno));
  lines_.push_back(Line{spec, *line, kind == Kind::events});
  return static_cast<LineId>(lines_.size() - 1);
}

std::expected<LineId, std::string> GpiodLines::request_output(const LineSpec& spec, bool initial) {
  return request(spec, Kind::output, initial);
}
std::expected<LineId, std::string> GpiodLines::request_input(const LineSpec& spec) {
  return request(spec, Kind::input, false);
}
std::expected<LineId, std::string> GpiodLines::request_input_events(const LineSpec& spec) {
  return request(spec, Kind::events, false);
}

std::expected<void, std::string> GpiodLines::set_value(LineId id, bool value) {
  Line& l = lines_.at(static_cast<std::size_t>(id));
  if (gpiod_line_set_value(l.handle, value ? 1 : 0) != 0)
    return std::unexpected(fmt::format("{}: write failed: {}", describe(l.spec), std::strerror(errno)));
  return {};
}

std::expected<bool, std::string> GpiodLines::get_value(LineId id) {
  Line& l = lines_.at(static_cast<std::size_t>(id));
  const int v = gpiod_line_get_value(l.handle);
  if (v < 0) return std::unexpected(fmt::format("{}: read failed: {}", describe(l.spec), std::strerror(errno)));
  return v != 0;
}

int GpiodLines::event_fd(LineId id) {
  const Line& l = lines_.at(static_cast<std::size_t>(id));
  return l.events ? gpiod_line_event_get_fd(l.handle) : -1;
}

std::expected<std::size_t, std::string> GpiodLines::read_events(LineId id, std::span<LineEvent> out) {
  Line& l = lines_.at(static_cast<std::size_t>(id));
  std::size_t n = 0;
  while (n < out.size()) {
    const timespec zero{0, 0};
    const int ready = gpiod_line_event_wait(l.handle, &zero);
    if (ready < 0)
      return std::unexpected(fmt::format("{}: event wait failed: {}", describe(l.spec), std::strerror(errno)));
    if (ready == 0) break;
    std::array<gpiod_line_event, 16> raw{};
    const unsigned want = static_cast<unsigned>(std::min(raw.size(), out.size() - n));
    const int got = gpiod_line_event_read_multiple(l.handle, raw.data(), want);
    if (got < 0)
      return std::unexpected(fmt::format("{}: event read failed: {}", describe(l.spec), std::strerror(errno)));
    for (int i = 0; i < got; ++i) {
      out[n++] = LineEvent{std::int64_t{raw[i].ts.tv_sec} * 1'000'000'000 + raw[i].ts.tv_nsec,
                           raw[i].event_type == GPIOD_LINE_EVENT_RISING_EDGE};
    }
    if (got < static_cast<int>(want)) break;
  }
  return n;
}

}  // namespace homing::gpiod
