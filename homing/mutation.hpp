#pragma once
// Mutation checks (tests/mutants): a second build of the engine, with
// HOMING_MUTATION_TESTING defined, can plant one known bug at run time, so
// that the whole-space campaign is shown to fail on a wrong product. In every
// other build planted() is constexpr false and the planted code is removed
// by the compiler; the engine stays a pure step function.
namespace homing {

enum class Mutant {
  none,
  drive_fault_as_sensor_alarm_elsewhere,  // a drive fault raises sensor_not_found on the next axis
  slave_keeps_own_direction,              // a slave homes in its own direction, not its master's
  racking_allowed_0_2_mm_past_limit,      // the gantry guard lets a pair rack 0.2 mm past max_misalignment
  reversed_encoder_unchecked,             // hard-stop homing by following error trusts an encoder counting backwards
  limit_switch_ignored_outside_homing,    // jogs, moves and braking run on past an active limit switch
  home_cam_search_ignores_limit_switch,   // cam_seek seeks on past the limit switch ahead instead of reversing
  gantry_side_turns_alone,                // a software gantry side arriving second at its edge turns a period early
};

#ifdef HOMING_MUTATION_TESTING
Mutant& planted_mutant();  // defined by the mutation test program
inline bool planted(Mutant m) { return planted_mutant() == m; }
#else
constexpr bool planted(Mutant) { return false; }
#endif

}  // namespace homing
