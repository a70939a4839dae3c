// homingctl trace: the FC 20 file of a real homing cycle as SVG, CSV and JSON,
// over TCP and RTU; the parser on malformed files (windows and label fitting:
// trace_fit_test.cpp).
#include <catch2/catch.hpp>
#include <fcntl.h>
#include <poll.h>

#include <atomic>
#include <regex>
#include <thread>

#include "tools_helpers.hpp"
#include "trace.hpp"

using namespace tools_test;


TEST_CASE("homingctl trace of a real cycle as SVG with axes, phases and the reference edge, as CSV and as JSON") {
  Daemon d;
  TempDir dir;
  REQUIRE(ctl(d, {"set", "axis.x.pull_off=2", "axis.x.home_position=-5", "axis.x.mode=switch_reapproach"}).code() == 0);
  auto r = ctl(d, {"trace", "x"});
  CHECK(r.code() == 1);  // no cycle yet
  CHECK(r.err.find("no trace for X") != std::string::npos);
  REQUIRE(ctl(d, {"home"}).code() == 0);

  const std::string svg_path = dir.file("x.svg"), csv_path = dir.file("x.csv");
  r = ctl(d, {"trace", "x", "--svg", svg_path, "--csv", csv_path});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("reference edge at") != std::string::npos);
  const std::string svg = read_file(svg_path);
  CHECK(svg.rfind("<svg xmlns=\"http://www.w3.org/2000/svg\"", 0) == 0);
  CHECK(svg.find("</svg>") != std::string::npos);
  for (const char* id : {"id=\"position\"", "id=\"velocity\"", "id=\"sensor\"", "id=\"time-axis\"", "id=\"phases\"",
                         "id=\"legend\"", "id=\"reference-edge\"", "id=\"title\""})
    CHECK(svg.find(id) != std::string::npos);
  CHECK(count_of(svg, "class=\"frame\"") == 3);  // three stacked plots
  CHECK(count_of(svg, "class=\"trace\"") == 3);
  CHECK(svg.find("time (ms)") != std::string::npos);
  CHECK(svg.find("position (mm)") != std::string::npos);
  for (const char* phase : {"seek", "stop", "back_off", "reapproach", "pull_off"}) {
    INFO(phase);
    CHECK(svg.find(std::string("class=\"phase-band\" data-phase=\"") + phase + "\"") != std::string::npos);
    CHECK(svg.find(std::string("class=\"legend-phase\"")) != std::string::npos);
    CHECK(std::regex_search(svg, std::regex(std::string("class=\"legend-phase\"[^>]*>") + phase + "<")));
  }
  CHECK(svg.find("reference edge -7.000 mm") != std::string::npos);
  CHECK(svg.find("id=\"alarm\"") == std::string::npos);

  const std::string csv = read_file(csv_path);
  CHECK(csv.rfind("time_ms,phase,position_mm,velocity_mm_per_s,sensor\n", 0) == 0);
  CHECK(count_of(csv, "\n") > 20);
  CHECK(csv.find(",seek,") != std::string::npos);
  CHECK(csv.find(",1\n") != std::string::npos);  // the sensor was active at some point

  auto j = json_of(ctl(d, {"trace", "x", "--json"}));
  CHECK(j["axis"] == "x");
  REQUIRE(j["reference_edge"].is_object());
  // Rest point = home_position; the edge is pull_off below it (negative homing).
  CHECK(j["reference_edge"]["position"] == Approx(-7.0).margin(0.01));
  CHECK(j["alarm"].is_null());
  CHECK(j["samples"].size() == count_of(csv, "\n") - 1);
  // The last sample rests at home_position.
  CHECK(j["samples"].back()[2].get<double>() == Approx(-5.0).margin(0.01));

  // CSV on stdout.
  r = ctl(d, {"trace", "x", "--csv", "-"});
  CHECK(r.code() == 0);
  CHECK(r.out == csv);
}

TEST_CASE("homingctl trace of a failing cycle shows the alarm") {
  Daemon d;
  TempDir dir;
  REQUIRE(ctl(d, {"set", "axis.x.max_seek_travel=40", "sim.x.fault=sensor_stuck_inactive"}).code() == 0);
  REQUIRE(ctl(d, {"home", "x"}).code() == 1);
  const std::string svg_path = dir.file("x.svg");
  auto r = ctl(d, {"trace", "x", "--svg", svg_path});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("home sensor not found within 40 mm") != std::string::npos);
  const std::string svg = read_file(svg_path);
  CHECK(svg.find("id=\"alarm\"") != std::string::npos);
  CHECK(svg.find("home sensor not found within 40 mm") != std::string::npos);
  CHECK(svg.find("id=\"reference-edge\"") == std::string::npos);  // none was found
  auto j = json_of(ctl(d, {"--json", "trace", "x"}));
  CHECK(j["alarm"]["name"] == "sensor_not_found");
  CHECK(j["reference_edge"].is_null());
}

TEST_CASE("homingctl over RTU: status, home and trace work on the serial line") {
  PtyPair pty;
  Daemon d({.extra = {"--rtu", pty.server_end()}});
  const std::vector<std::string> rtu{HOMINGCTL_PATH, "--rtu", pty.client_end(), "--baud", "19200", "--parity", "E"};
  auto run = [&](std::vector<std::string> args) {
    std::vector<std::string> argv = rtu;
    argv.insert(argv.end(), args.begin(), args.end());
    return run_program(argv, 60s);
  };
  auto r = run({"home"});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
  }
  r = run({"status", "--json"});
  CHECK(json_of(r)["state"] == "homed");
  // Function 20 is framed by the module's own RTU framer (libmodbus cannot).
  r = run({"trace", "y"});
  {
    SHOW(r);
    CHECK(r.code() == 0);
    CHECK(r.out.rfind("Y: ", 0) == 0);
    CHECK(r.out.find("reference edge at") != std::string::npos);
  }
  r = run({"get", "axis.y.homed"});
  CHECK(r.out == "axis.y.homed = 1\n");
}

// The RTU framing of FC 20 in homingctl, against a responder on a pty that
// answers like a server that supports it (CRC checked both ways).
TEST_CASE("homingctl reads an FC 20 file over RTU from a device that serves it") {
  PtyPair pty;
  std::vector<std::uint16_t> file(10 + 8 * 3, 0);
  file[0] = 3;
  file[1] = 10;
  file[2] = file[3] = 0xFFFF;
  for (int i = 0; i < 3; ++i) {
    file[10 + 8 * i + 1] = static_cast<std::uint16_t>(i * 7);
    file[10 + 8 * i + 2] = 3;
    file[10 + 8 * i + 4] = static_cast<std::uint16_t>(1000 * (i + 1));
  }
  auto crc16 = [](const std::uint8_t* p, std::size_t n) {
    std::uint16_t crc = 0xFFFF;
    for (std::size_t i = 0; i < n; ++i) {
      crc ^= p[i];
      for (int b = 0; b < 8; ++b) crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001) : crc >> 1;
    }
    return crc;
  };
  const int fd = ::open(pty.server_end().c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
  REQUIRE(fd >= 0);
  std::atomic<bool> stop{false};
  std::atomic<int> served{0}, bad{0};
  std::thread responder([&] {
    std::vector<std::uint8_t> req;
    while (!stop) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      std::uint8_t buf[64];
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n <= 0) continue;
      req.insert(req.end(), buf, buf + n);
      if (req.size() < 12) continue;
      const std::uint16_t crc = crc16(req.data(), 10);
      if (req[0] != 1 || req[1] != 20 || req[2] != 7 || req[3] != 6 || req[10] != (crc & 0xFF) || req[11] != (crc >> 8)) {
        ++bad;
        req.clear();
        continue;
      }
      const int record = (req[6] << 8) | req[7], length = (req[8] << 8) | req[9];
      std::vector<std::uint8_t> rsp{1, 20, static_cast<std::uint8_t>(2 + 2 * length), static_cast<std::uint8_t>(1 + 2 * length), 6};
      for (int i = 0; i < length; ++i) {
        const std::uint16_t w = file[static_cast<std::size_t>(record + i)];
        rsp.push_back(static_cast<std::uint8_t>(w >> 8));
        rsp.push_back(static_cast<std::uint8_t>(w & 0xFF));
      }
      const std::uint16_t c = crc16(rsp.data(), rsp.size());
      rsp.push_back(static_cast<std::uint8_t>(c & 0xFF));
      rsp.push_back(static_cast<std::uint8_t>(c >> 8));
      (void)::write(fd, rsp.data(), rsp.size());
      ++served;
      req.clear();
    }
  });
  auto r = run_program({HOMINGCTL_PATH, "--rtu", pty.client_end(), "trace", "x", "--csv", "-"}, 30s);
  stop = true;
  responder.join();
  ::close(fd);
  SHOW(r);
  CHECK(r.code() == 0);
  CHECK(r.out == "time_ms,phase,position_mm,velocity_mm_per_s,sensor\n0,seek,1.000,0.000,0\n7,seek,2.000,0.000,0\n"
                 "14,seek,3.000,0.000,0\n");
  CHECK(served == 2);  // header, then the samples
  CHECK(bad == 0);
}

TEST_CASE("trace files: header, samples, and malformed files") {
  std::vector<std::uint16_t> w(10 + 8 * 2, 0);
  w[0] = 2;
  w[1] = 10;  // 1 ms
  w[2] = 0;
  w[3] = 5;  // edge at 5 ms
  const auto edge = static_cast<std::uint32_t>(static_cast<std::int32_t>(-1500));
  w[4] = static_cast<std::uint16_t>(edge >> 16);
  w[5] = static_cast<std::uint16_t>(edge & 0xFFFF);
  w[9] = 9;
  w[10 + 1] = 0;
  w[10 + 2] = 3;  // seek
  w[10 + 8 + 1] = 9;
  w[10 + 8 + 2] = 9;  // pull_off
  w[10 + 8 + 7] = 1;
  const auto t = homingctl::parse_trace(0, w);
  CHECK(t.samples.size() == 2);
  CHECK(t.interval_ms == Approx(1.0));
  REQUIRE(t.edge_time_ms);
  CHECK(*t.edge_time_ms == 5);
  CHECK(t.edge_position_mm == Approx(-1.5));
  CHECK(t.duration_ms == 9);
  CHECK(t.samples[1].phase == homing::Phase::pull_off);
  CHECK(t.samples[1].sensor);
  const std::string svg = homingctl::trace_svg(t, "");
  CHECK(svg.find("id=\"reference-edge\"") != std::string::npos);
  CHECK(homingctl::trace_csv(t) == "time_ms,phase,position_mm,velocity_mm_per_s,sensor\n0,seek,0.000,0.000,0\n9,pull_off,0.000,0.000,1\n");

  w.resize(20);  // announces 2 samples, holds 1.25
  CHECK_THROWS_WITH(homingctl::parse_trace(0, w), Catch::Contains("announces 2 samples"));
  CHECK_THROWS(homingctl::parse_trace(0, std::vector<std::uint16_t>(5, 0)));
  w.assign(10, 0);
  w[2] = w[3] = 0xFFFF;
  CHECK_FALSE(homingctl::parse_trace(0, w).edge_time_ms);
}
