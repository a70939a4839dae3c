#include "cli.hpp"

#include <fmt/format.h>

namespace homingctl {

void Context::finish_options() {
  co.parity = parity[0];
  co.word_order = word_order == "low-first" ? registers::WordOrder::low_first : registers::WordOrder::high_first;
  ao.wait = !no_wait;
  ao.timeout_s = timeout_s;
  ao.poll_s = co.rtu.empty() ? 0.05 : 0.3;
}

Connection& Context::connection() {
  if (!conn_) conn_ = std::make_unique<Connection>(co);
  return *conn_;
}

int Context::report(const ActionResult& r) const {
  if (json) print_json(r.json);
  else if (r.exit_code == 0) fmt::print("{}\n", r.message);
  else fmt::print(stderr, "{}\n", r.message);
  return r.exit_code;
}

void print_json(const nlohmann::json& j) { fmt::print("{}\n", j.dump(2)); }

CLI::App* Commands::add(const std::string& name, const std::string& help, Run run) {
  CLI::App* sub = app_.add_subcommand(name, help);
  commands_.emplace_back(sub, std::move(run));
  return sub;
}

const Run* Commands::chosen() const {
  for (const auto& [sub, run] : commands_)
    if (*sub) return &run;
  return nullptr;
}

void Commands::add_wait_options(CLI::App* sub, Context& ctx) {
  sub->add_flag("--no-wait", ctx.no_wait, "return once the module took the command");
  sub->add_option("--timeout-s", ctx.timeout_s, "give up waiting after this long")->capture_default_str();
}

}  // namespace homingctl
