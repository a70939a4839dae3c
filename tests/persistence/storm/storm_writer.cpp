// settings_storm_writer DB [backup_interval_ms] [seed]
// Commits a storm of settings writes and prints one line per acknowledged
// commit ("ack name=value ..."), written with a single write(2) AFTER commit()
// returned, like a Modbus answer. The kill -9 test kills it at a random time.
// Values come from one increasing counter, so a key's stored value must be >=
// its last acknowledged value. storm.pair.a and storm.pair.b are always written
// together (one multi-register transaction) and must always be equal.
#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdio>
#include <random>
#include <string>

#include "persistence/settings_store.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s DB [backup_interval_ms] [seed]\n", argv[0]);
    return 2;
  }
  const std::string db = argv[1];
  persistence::StoreOptions o;
  o.backup_min_interval = std::chrono::milliseconds(argc > 2 ? std::stoll(argv[2]) : 1000);
  o.logger = std::make_shared<spdlog::logger>("storm", std::make_shared<spdlog::sinks::null_sink_mt>());
  o.audit_max_rows = 500;
  std::mt19937 rng(argc > 3 ? static_cast<unsigned>(std::stoul(argv[3])) : 1u);

  std::vector<persistence::SettingDefault> defaults;
  for (int k = 0; k < 8; ++k) defaults.push_back({"storm.k" + std::to_string(k), 0});
  defaults.push_back({"storm.pair.a", 0});
  defaults.push_back({"storm.pair.b", 0});

  persistence::OpenReport report;
  auto store = persistence::SettingsStore::open(db, defaults, report, o);
  if (!store) {
    std::fprintf(stderr, "open failed: %s\n", store.error().message.c_str());
    return 3;
  }
  std::int64_t counter = 0;
  for (const auto& [name, v] : store->load()) counter = std::max(counter, v);
  const std::string ready = "ready " + std::string(persistence::outcome_name(report.outcome)) + "\n";
  if (::write(1, ready.data(), ready.size()) < 0) return 4;

  const persistence::ChangeSource source{"tcp", "storm"};
  for (;;) {
    ++counter;
    std::vector<persistence::SettingWrite> w;
    if (rng() % 3 == 0) {
      w = {{"storm.pair.a", counter}, {"storm.pair.b", counter}};
    } else {
      w = {{"storm.k" + std::to_string(rng() % 8), counter}};
    }
    auto r = store->commit(w, source);
    if (!r) {
      std::fprintf(stderr, "commit failed: %s\n", r.error().message.c_str());
      return 5;
    }
    std::string line = "ack";
    for (const auto& x : w) line += " " + x.name + "=" + std::to_string(x.value);
    line += "\n";
    if (::write(1, line.data(), line.size()) < 0) return 4;
  }
}
