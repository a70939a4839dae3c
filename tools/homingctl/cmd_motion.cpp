// home, refcheck, unhome, measure, abort, reset, jog, move: commands that move (or stop) the machine,
// each waiting for its outcome unless --no-wait.
#include "actions.hpp"
#include "cli.hpp"

namespace homingctl {

namespace {

struct JogOptions {
  std::string axis, direction;
  int ms = 500;
};

struct MoveOptions {
  std::string axis, target;
};

int jog_axis(Context& ctx, const JogOptions& o) {
  const int direction = (o.direction == "+" || o.direction == "plus") ? 1 : -1;
  return ctx.report(jog(ctx.connection(), o.axis, direction, o.ms, ctx.ao));
}

}  // namespace

void add_motion_commands(Commands& commands, Context& ctx) {
  auto targets = std::make_shared<std::vector<std::string>>();
  auto* home_cmd = commands.add("home", "home all axes (default) or the named ones, and wait for the result",
                                [targets](Context& c) {
                                  const HomeTargets t = home_targets(*targets);  // a bad name before connecting
                                  return c.report(home(c.connection(), t, c.ao));
                                });
  home_cmd->add_option("axes", *targets, "all | x y z a b c");
  commands.add_wait_options(home_cmd, ctx);

  auto refcheck_axis = std::make_shared<std::string>();
  auto* refcheck_cmd = commands.add(
      "refcheck",
      "after a restart, check an axis whose last stop was clean (trust last_stop_clean) against its switch edge "
      "instead of a full cycle: refcheck x",
      [refcheck_axis](Context& c) { return c.report(refcheck(c.connection(), *refcheck_axis, c.ao)); });
  refcheck_cmd->add_option("axis", *refcheck_axis, "x y z a b c")->required();
  commands.add_wait_options(refcheck_cmd, ctx);

  auto unhome_axis = std::make_shared<std::string>();
  auto* unhome_cmd = commands.add(
      "unhome",
      "forget an axis's reference (and its gantry partner's) without moving, e.g. after squaring a gantry or moving "
      "a carriage by hand: unhome y",
      [unhome_axis](Context& c) { return c.report(unhome(c.connection(), *unhome_axis, c.ao)); });
  unhome_cmd->add_option("axis", *unhome_axis, "x y z a b c")->required();

  auto measure_axis = std::make_shared<std::string>();
  auto measure_apply = std::make_shared<bool>(false);
  auto* measure_cmd = commands.add(
      "measure",
      "commissioning: home an axis, travel at latch feedrate to the opposite limit switch or hard stop, and print "
      "the usable travel with the soft limits and max_seek_travel that fit it: measure x [--apply]",
      [measure_axis, measure_apply](Context& c) {
        return c.report(measure(c.connection(), *measure_axis, *measure_apply, c.ao));
      });
  measure_cmd->add_option("axis", *measure_axis, "x y z a b c")->required();
  measure_cmd->add_flag("--apply", *measure_apply, "write the soft limits and max_seek_travel found (checked, audited)");
  commands.add_wait_options(measure_cmd, ctx);

  auto* abort_cmd = commands.add("abort", "stop every motion (a running homing latches 'aborted')",
                                 [](Context& c) { return c.report(abort_motion(c.connection(), c.ao)); });
  commands.add_wait_options(abort_cmd, ctx);
  commands.add("reset", "clear latched alarms once their cause is gone",
               [](Context& c) { return c.report(reset_alarm(c.connection(), c.ao)); });

  auto jog_options = std::make_shared<JogOptions>();
  auto* jog_cmd = commands.add("jog", "jog an axis for a while: jog x + --ms 500",
                               [jog_options](Context& c) { return jog_axis(c, *jog_options); });
  jog_cmd->add_option("axis", jog_options->axis, "x y z a b c")->required();
  jog_cmd->add_option("direction", jog_options->direction, "+ or -")
      ->required()
      ->check(CLI::IsMember({"+", "-", "plus", "minus"}));
  jog_cmd->add_option("--ms", jog_options->ms, "how long the jog coil is held")
      ->check(CLI::Range(1, 600000))
      ->capture_default_str();
  commands.add_wait_options(jog_cmd, ctx);

  auto move_options = std::make_shared<MoveOptions>();
  auto* move_cmd = commands.add("move", "move an axis to a position: move x 12.5 (mm or deg)", [move_options](Context& c) {
    return c.report(move(c.connection(), move_options->axis, move_options->target, c.ao));
  });
  move_cmd->add_option("axis", move_options->axis, "x y z a b c")->required();
  move_cmd->add_option("target", move_options->target, "target position in the axis unit")->required();
  commands.add_wait_options(move_cmd, ctx);
}

}  // namespace homingctl
