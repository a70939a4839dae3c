// Homed only in the frame it was homed in (home_frame.hpp).
#include "engine.hpp"

namespace homing {

// Run at the start of a period (a change of settings since the last one
// unhomes before anything moves) and at its end (an axis homed in this
// period keeps the frame it was homed in).
void Engine::keep_home_frames(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    if (!run.homed) {
      run.homed_in.reset();
      continue;
    }
    const HomeFrame now = home_frame(settings.axes[a]);
    if (!run.homed_in) run.homed_in = now;
    else if (*run.homed_in != now) {
      run.homed = false;
      run.homed_in.reset();
    }
  }
}

}  // namespace homing
