#pragma once
// The generator's state and its steps (machine_gen.cpp: the geometry of
// axes and gantries, roles, sequence; causes_gen.cpp: settings made wrong
// on purpose, faults and events). Internal to the campaign's generator.
#include <functional>
#include <vector>

#include "dice.hpp"
#include "machine.hpp"

namespace campaign::gen {

inline double mirror(double dir, double x) { return dir < 0 ? x : -x; }
inline double per_min(double mm_per_s) { return mm_per_s * 60.0; }

// What a pair shares when its master's motion settings are drawn.
struct PairDraw {
  bool pair = false;
  double accel = 1e9;      // the slave's own acceleration
  double debounce_ms = 0;  // the slave's own
  double bounce_ms = 0;
  double hysteresis = 0;   // the slave's sensor's
  double misalignment = 1e9;
};
// A home_cam axis in the frame (the seek toward negative): its cam, where the
// carriage starts, its two limit switches and what lies beyond them.
struct CamFrame {
  double top = 0, bottom = 0;     // the cam
  double start = 0;
  double seek_side = 0;           // the limit switch the seek meets
  double far_side = 0;            // the other
  double stop_beyond_seek = 0;    // the mechanical stops: this far beyond overtravel
  double stop_beyond_far = 0;
  double seek_margin = 0;         // max_seek_travel beyond the whole travel and overtravel
};
struct Gen {
  Dice d;
  Machine m;
  explicit Gen(std::uint64_t seed) : d(seed, 1) { m.seed = seed; }
  // How far past its trigger a seek may come to rest, a late period included.
  double overshoot(const AxisSettings& s) const;
  // Motion settings every homing mode can use, drawn for this axis (and its
  // slave: the pair stops with the lower acceleration and the longer debounce).
  void draw_motion(AxisSettings& s, sim::AxisConfig& c, const PairDraw& pd);
  // Predicted reference edge in the frame, for a cam edge at edge_f.
  static double reference_f(const AxisSettings& e, const sim::AxisConfig& c, double edge_f, double index_r);
  // Index pulses index_r beyond the predicted release, well inside a pitch.
  static void place_index(sim::AxisConfig& c, double dir, double pitch, double release_f, double index_r);
  void set_cam(std::size_t a, double dir, double edge_f, double cam_len, double start_f);
  void set_stops(std::size_t a, double dir, double in_f, double out_f);
  // Soft limits and final position around the home position; returns how far
  // toward the sensor the soft limits let a jog go (from the rest point).
  // far_away: how far from the home position (away from the sensor) the axis
  // may be left between cycles (final move, jogs and moves within the limits).
  // room_max: how far toward the sensor from the home position the axis may
  // be left (on the cam at most as deep as a back-off can release).
  double limits(AxisSettings& s, double hyst, bool shared, double room_max, double& far_away);
  // Geometry of a switch or pushing axis (plain or master). slack: extra
  // travel its gantry partner may need on top of its own (0 for a plain axis).
  void place_switch(std::size_t a, double hyst_pair, double slack, bool shared, double& index_r);
  // An axis homed without a search: manual, absolute, disabled. Its cam lies
  // out of the way; stops far from where it may move.
  void still_axis(std::size_t a);
  // A hard-stop axis: no cam, its stop within max_seek_travel, a drive whose
  // stall detection takes its own time.
  void hard_stop_axis(std::size_t a);
  void drive_axis(std::size_t a);  // drive mode: a still axis whose drive homes itself

  // The slave of master mi: its own sensor, placed so that the beam starts
  // square to within the skew drawn (or beyond the limit: a bad-skew run).
  void place_slave(std::size_t si, std::size_t mi, const PairDraw& pd, double budget, double slack,
                   double master_index_r);

  // A gantry: master mi (a switch or pushing mode), slave si.
  void gantry(std::size_t mi, std::size_t si, bool commutator);
  void roles_and_modes();
  void sequence();
  void unsequenced_soft_limits();  // no dice: after every other draw
  // --- causes -------------------------------------------------------------
  std::vector<std::size_t> axes_where(const std::function<bool(std::size_t)>& pred) const;
  template <class V>
  bool pick_axis(const V& list, std::size_t& out) {
    if (list.empty()) return false;
    out = list[static_cast<std::size_t>(d.integer(0, static_cast<int>(list.size()) - 1))];
    return true;
  }
  bool is_switch_axis(std::size_t a) const;
  void invalid_settings();
  void causes();
  double axis_time_estimate(std::size_t a) const;
  void events();
  void indexers();
  void limit_switches();
  void following_error();
  void failure_policy();
  // home_cam axes (home_cam_gen.cpp), from their own dice after everything else.
  bool may_become_home_cam(std::size_t a) const;
  void home_cams();
  CamFrame home_cam_axis(std::size_t a, Dice& hc);
  void place_home_cam(std::size_t a, const CamFrame& f);  // the simulated machine and max_seek_travel
  void home_cam_cause(std::size_t a, CamFrame f, Dice& hk);
  // Limit switches within reach (limits_reach_gen.cpp), from their own dice.
  void limits_in_reach();
  void limit_in_reach(std::size_t a, Dice& lr);
  // refcheck_tolerance, and hard stops within a measurement's reach (machine_gen.cpp), from their own dice.
  void travel_ends();
  Machine build();
};

}  // namespace campaign::gen
