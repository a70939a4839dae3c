// Homed only in the frame it was homed in (home_frame.hpp).
#include "engine.hpp"
#include "gantry.hpp"

namespace homing {

// Run at the start of a period: a change of settings since the last one
// unhomes before anything moves.
void Engine::keep_home_frames(const Settings& settings) {
  AxisMask pairs_lost = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    if (run.home && *run.home != home_frame(settings.axes[a])) {
      // A gantry pair shares one reference (unhome.cpp): a change of one
      // side's frame (a slave's own switch_compensation) unhomes both, the
      // pair it was homed in as well as the one it is in now.
      pairs_lost |= axis_bit(a);
      if (const int m = static_cast<int>(run.home->slave_of) - 1; m >= 0 && m < static_cast<int>(kAxisCount))
        pairs_lost |= axis_bit(static_cast<std::size_t>(m));
      if (const int m = gantry_master(settings, a); m >= 0) pairs_lost |= axis_bit(static_cast<std::size_t>(m));
      if (const int s = gantry_slave(settings, a); s >= 0) pairs_lost |= axis_bit(static_cast<std::size_t>(s));
      run.home.reset();
    }
    // A stored position is where the axis rested in its frame then.
    if (run.restored && *run.restored != home_frame(settings.axes[a])) run.restored.reset();
  }
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(pairs_lost & axis_bit(a))) continue;
    axes_[a].home.reset();
    axes_[a].pair_square_mm.reset();
  }
}

}  // namespace homing
