#pragma once
// Small helpers shared by the benchmark programs: a monotonic clock,
// percentiles of a latency sample, "--key value" argument parsing, and
// reading a whole reply from a socket, the process's own CPU and scheduler
// counters over a measured stretch.
#include <sys/resource.h>
#include <sys/socket.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace bench {

inline std::int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

// n bytes from a blocking socket; false when it closes or fails first.
inline bool recv_exact(int fd, std::uint8_t* p, std::size_t n) {
  std::size_t got = 0;
  while (got < n) {
    const ssize_t r = ::recv(fd, p + got, n - got, 0);
    if (r <= 0) {
      if (r < 0 && errno == EINTR) continue;
      return false;
    }
    got += static_cast<std::size_t>(r);
  }
  return true;
}

// Value below which a fraction q of the sample lies (nearest rank).
inline double percentile(std::vector<double>& v, double q) {
  if (v.empty()) return 0;
  std::size_t k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  k = std::clamp<std::size_t>(k, 1, v.size()) - 1;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// "--key value" and "--flag" arguments; unknown keys are an error.
class Args {
 public:
  Args(int argc, char** argv, const std::map<std::string, std::string>& defaults) : values_(defaults) {
    for (int i = 1; i < argc; ++i) {
      std::string a = argv[i];
      if (a.rfind("--", 0) != 0) fail(argv[0], "unexpected argument " + a);
      a = a.substr(2);
      auto it = values_.find(a);
      if (it == values_.end()) fail(argv[0], "unknown option --" + a);
      if (it->second == "false" || it->second == "true") {
        it->second = "true";
      } else {
        if (i + 1 >= argc) fail(argv[0], "--" + a + " needs a value");
        it->second = argv[++i];
      }
    }
  }
  const std::string& str(const std::string& k) const { return values_.at(k); }
  long num(const std::string& k) const { return std::strtol(str(k).c_str(), nullptr, 10); }
  double real(const std::string& k) const { return std::strtod(str(k).c_str(), nullptr); }
  bool flag(const std::string& k) const { return str(k) == "true"; }

 private:
  [[noreturn]] void fail(const char* prog, const std::string& why) {
    std::fprintf(stderr, "%s: %s\noptions (defaults):", prog, why.c_str());
    for (const auto& [k, v] : values_) std::fprintf(stderr, " --%s %s", k.c_str(), v.c_str());
    std::fprintf(stderr, "\n");
    std::exit(2);
  }
  std::map<std::string, std::string> values_;
};

// Lateness histogram with 1 µs buckets, the same shape as homingd's LoopStats.
struct LatenessHistogram {
  static constexpr std::size_t kBuckets = 4096;
  std::vector<std::uint64_t> counts = std::vector<std::uint64_t>(kBuckets, 0);
  double max_us = 0;
  std::uint64_t total = 0;
  void add(double us) {
    max_us = std::max(max_us, us);
    ++counts[static_cast<std::size_t>(std::clamp(us, 0.0, double(kBuckets - 1)))];
    ++total;
  }
  double percentile_us(double q) const {
    if (total == 0) return 0;
    const auto wanted = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(total)));
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < kBuckets; ++i) {
      seen += counts[i];
      if (seen >= wanted) return i == kBuckets - 1 ? max_us : static_cast<double>(i);
    }
    return max_us;
  }
};

// The process's own CPU and scheduler counters, read before and after the
// stretch a program measures, so run_benchmarks.py can explain a figure by
// what the program spent on it (getrusage: every thread of the process;
// /proc/self/schedstat: run-queue wait and time slices of the calling thread,
// which is the only one in loop_floor and sqlite_commit).
struct SelfCounters {
  double user_us = 0, sys_us = 0;
  long vcs = 0, ivcs = 0;
  double rq_wait_us = 0;
  long slices = 0;

  static SelfCounters now() {
    SelfCounters c;
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    c.user_us = ru.ru_utime.tv_sec * 1e6 + ru.ru_utime.tv_usec;
    c.sys_us = ru.ru_stime.tv_sec * 1e6 + ru.ru_stime.tv_usec;
    c.vcs = ru.ru_nvcsw;
    c.ivcs = ru.ru_nivcsw;
    if (std::FILE* f = std::fopen("/proc/thread-self/schedstat", "r")) {
      unsigned long long run_ns = 0, wait_ns = 0, n = 0;
      if (std::fscanf(f, "%llu %llu %llu", &run_ns, &wait_ns, &n) == 3) {
        c.rq_wait_us = wait_ns / 1e3;
        c.slices = static_cast<long>(n);
      }
      std::fclose(f);
    }
    return c;
  }
  // " cpu_user_us=... cpu_sys_us=... vcs=... ivcs=... rq_wait_us=... slices=..." of (this - before),
  // appended to a RESULT line.
  std::string since(const SelfCounters& b) const {
    char buf[256];
    std::snprintf(buf, sizeof buf, " cpu_user_us=%.0f cpu_sys_us=%.0f vcs=%ld ivcs=%ld rq_wait_us=%.0f slices=%ld",
                  user_us - b.user_us, sys_us - b.sys_us, vcs - b.vcs, ivcs - b.ivcs, rq_wait_us - b.rq_wait_us,
                  slices - b.slices);
    return buf;
  }
};

}  // namespace bench
