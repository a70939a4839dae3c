// README: "Function 20 (read file record) returns the trace of the last
// homing cycle of each axis ... per control period the time, phase,
// position, velocity and sensor, plus the reference edge and the alarm", and
// `--period-us` sets the control period. The real daemon homes on its
// simulator; the trace is read with Modbus/TCP framed here on a plain socket
// (not homingctl, not libmodbus, which cannot parse function 20's answer) and
// decoded from the layout in hmi_maps/README.md.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>

#include "daemon.hpp"
#include "homing/phases.hpp"
#include "homing/status.hpp"

using namespace e2e;
using homing::Phase;

namespace {

constexpr std::uint8_t kReadFileRecord = 0x14;
constexpr int kHeaderWords = 10, kSampleWords = 8, kChunkWords = 120;

struct Sample {
  std::uint32_t time_ms;
  int phase;
  std::int32_t position_um;
  std::int32_t velocity_um_per_s;
  int sensor;
};

struct Trace {
  int count = 0;
  int interval_01ms = 0;
  std::optional<std::uint32_t> edge_time_ms;
  std::int32_t edge_um = 0;
  int alarm = 0, alarm_phase = 0;
  std::uint32_t duration_ms = 0;
  std::vector<Sample> samples;
};

std::uint32_t u32(const std::vector<std::uint16_t>& w, std::size_t at) {
  return (std::uint32_t{w[at]} << 16) | w[at + 1];
}

// One sub-request per PDU: file `file`, records [first, first + words).
std::vector<std::uint8_t> read_request(int file, int first, int words) {
  return {kReadFileRecord, 7, 6,
          static_cast<std::uint8_t>(file >> 8), static_cast<std::uint8_t>(file),
          static_cast<std::uint8_t>(first >> 8), static_cast<std::uint8_t>(first),
          static_cast<std::uint8_t>(words >> 8), static_cast<std::uint8_t>(words)};
}

// The words of a one-sub-request answer: 14, byte count, sub length, 6, data.
std::vector<std::uint16_t> words_of(const std::vector<std::uint8_t>& pdu, int words) {
  REQUIRE(pdu.size() == 4u + 2u * words);
  REQUIRE(pdu[0] == kReadFileRecord);
  REQUIRE(pdu[1] == 2 + 2 * words);
  REQUIRE(pdu[2] == 1 + 2 * words);
  REQUIRE(pdu[3] == 6);
  std::vector<std::uint16_t> out;
  for (int i = 0; i < words; ++i) out.push_back(static_cast<std::uint16_t>(pdu[4 + 2 * i] << 8 | pdu[5 + 2 * i]));
  return out;
}

// The file of one axis (1 = X ... 6 = C): the header, then every sample in
// chunks that fit a PDU, pipelined on one connection.
Trace read_trace(int port, int file) {
  Trace t;
  const auto head = words_of(raw_tcp_transaction(port, 1, read_request(file, 0, kHeaderWords)), kHeaderWords);
  t.count = head[0];
  t.interval_01ms = head[1];
  if (u32(head, 2) != 0xFFFFFFFFu) t.edge_time_ms = u32(head, 2);
  t.edge_um = static_cast<std::int32_t>(u32(head, 4));
  t.alarm = head[6];
  t.alarm_phase = head[7];
  t.duration_ms = u32(head, 8);

  const int total = t.count * kSampleWords;
  std::vector<std::pair<std::uint8_t, std::vector<std::uint8_t>>> requests;
  for (int at = 0; at < total; at += kChunkWords)
    requests.push_back({1, read_request(file, kHeaderWords + at, std::min(kChunkWords, total - at))});
  const auto replies = raw_tcp_pipeline(port, requests, 10s);
  REQUIRE(replies.size() == requests.size());
  std::vector<std::uint16_t> body;
  for (std::size_t i = 0; i < replies.size(); ++i) {
    REQUIRE(replies[i].first == 1 + i);
    const int words = std::min(kChunkWords, total - static_cast<int>(i) * kChunkWords);
    const auto w = words_of(replies[i].second, words);
    body.insert(body.end(), w.begin(), w.end());
  }
  for (int i = 0; i < t.count; ++i) {
    const std::size_t at = static_cast<std::size_t>(i) * kSampleWords;
    t.samples.push_back({u32(body, at), body[at + 2], static_cast<std::int32_t>(u32(body, at + 3)),
                         static_cast<std::int32_t>(u32(body, at + 5)), body[at + 7]});
  }
  return t;
}

// Homes the axes of the mask in one cycle and waits for it to end homed.
void home(Client& c, std::int64_t axes) {
  const auto before = c.read("status.homing_cycles");
  REQUIRE(c.write("cmd.home_axes", axes) == 0);
  REQUIRE(wait_until(
      [&] { return c.read("status.homing") == 0 && (c.read("status.homing_cycles") > before || c.read("status.alarm")); },
      60s, 20ms));
  REQUIRE(c.read("status.alarm") == 0);
  REQUIRE(c.read("status.homing_cycles") == before + 1);
}

std::string ax(char axis, const char* field) { return std::string("axis.") + axis + "." + field; }

// What the trace of an axis homed in mode 2 (negative direction, release
// edge, no alarm) must show against the module's own registers.
void check_homed_trace(Client& c, const Trace& t, char axis) {
  INFO("axis " << axis);
  REQUIRE(t.count > 10);
  REQUIRE(t.samples.size() == static_cast<std::size_t>(t.count));
  CHECK(t.alarm == 0);
  CHECK(t.interval_01ms > 0);
  // Machine time since the cycle started, in order, within the cycle.
  CHECK(t.samples.front().time_ms == 0);
  for (std::size_t i = 1; i < t.samples.size(); ++i) REQUIRE(t.samples[i].time_ms >= t.samples[i - 1].time_ms);
  CHECK(t.samples.back().time_ms <= t.duration_ms);
  CHECK(t.duration_ms - t.samples.back().time_ms <= 1 + t.interval_01ms / 10u);

  // The axis went through its phases in order: seek before stop before pull-off.
  auto first = [&](Phase p) {
    const auto it = std::find_if(t.samples.begin(), t.samples.end(),
                                 [&](const Sample& s) { return s.phase == static_cast<int>(p); });
    return it == t.samples.end() ? -1 : static_cast<int>(it - t.samples.begin());
  };
  const int seek = first(Phase::seek), stop = first(Phase::stop), back = first(Phase::back_off),
            pull = first(Phase::pull_off);
  REQUIRE(seek >= 0);
  CHECK(stop > seek);
  CHECK(back > stop);
  CHECK(pull > back);

  // Seek at seek_feedrate toward negative positions.
  std::int32_t fastest_seek = 0;
  for (const Sample& s : t.samples)
    if (s.phase == static_cast<int>(Phase::seek)) fastest_seek = std::min(fastest_seek, s.velocity_um_per_s);
  CHECK(fastest_seek == Approx(-c.read(ax(axis, "seek_feedrate")) * 1000.0 / 60).margin(2));
  // The sensor came on during the seek (it ends the seek) and was off at the end.
  CHECK(t.samples[static_cast<std::size_t>(stop)].sensor == 1);
  CHECK(t.samples[static_cast<std::size_t>(seek)].sensor == 0);
  CHECK(t.samples.back().sensor == 0);

  // It ends at rest where the module says the axis is, in the final coordinates.
  // The last sample is the cycle's last period: braking ends in it, so at
  // most one period's worth of the acceleration is left.
  const double one_period_um_per_s = c.read(ax(axis, "acceleration")) * 1000.0 * t.interval_01ms / 1e4;
  CHECK(std::abs(t.samples.back().velocity_um_per_s) <= one_period_um_per_s);
  const auto position = c.read(ax(axis, "position"));
  CHECK(std::abs(t.samples.back().position_um - position) <= 1);
  // The reference edge: found before the pull-off began, pull_off below the rest point.
  REQUIRE(t.edge_time_ms);
  CHECK(*t.edge_time_ms <= t.samples[static_cast<std::size_t>(pull)].time_ms);
  CHECK(*t.edge_time_ms >= t.samples[static_cast<std::size_t>(back)].time_ms);
  CHECK(std::abs(t.edge_um - (position - c.read(ax(axis, "pull_off")))) <= 1);
}

bool is_power_of_two(int n) { return n > 0 && (n & (n - 1)) == 0; }

}  // namespace

TEST_CASE("a plain Modbus/TCP client reads each axis's homing trace with function 20 and it shows the cycle") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  c.set("axis.z.pull_off", um(1.5));
  home(c, 0b111);  // X, Y, Z in their default sequence steps
  const Trace z = read_trace(d.port(), 3);
  check_homed_trace(c, z, 'z');
  const Trace x = read_trace(d.port(), 1);
  check_homed_trace(c, x, 'x');
  // X waited for Z's step: it was not moving while Z sought.
  for (const Sample& s : x.samples) {
    if (s.time_ms > static_cast<std::uint32_t>(z.edge_time_ms.value_or(0))) break;
    CHECK(s.velocity_um_per_s == 0);
  }
  // One cycle, one clock: both files cover the same cycle.
  CHECK(x.duration_ms == z.duration_ms);
  // An axis that took no part has an empty trace.
  const Trace a = read_trace(d.port(), 4);
  CHECK(a.count == 0);
}

TEST_CASE("homingd --period-us sets the control period: the homing trace has one sample per period of that length") {
  for (const int period_us : {1000, 1500}) {
    INFO("--period-us " << period_us);
    Daemon d({.time_scale = 10, .extra = {"--period-us", std::to_string(period_us)}});
    Client c = Client::tcp(d.port());
    home(c, 0b100);  // Z
    const Trace z = read_trace(d.port(), 3);
    REQUIRE(z.count > 10);
    // One sample per control period, every other one dropped each time the
    // 1200-sample buffer filled: the period times a power of two.
    const int period_01ms = period_us / 100;
    INFO("interval " << z.interval_01ms / 10.0 << " ms");
    REQUIRE(z.interval_01ms % period_01ms == 0);
    CHECK(is_power_of_two(z.interval_01ms / period_01ms));
    // And the samples' machine times are that far apart: a late period is
    // cut into engine steps no longer than the period, so never more. The
    // last sample is kept whatever the stride and is left out.
    const auto& s = z.samples;
    const double mean_ms = double(s[s.size() - 2].time_ms - s.front().time_ms) / double(s.size() - 2);
    CHECK(mean_ms <= z.interval_01ms / 10.0 * 1.02);
    CHECK(mean_ms >= z.interval_01ms / 10.0 * 0.7);
  }
}
