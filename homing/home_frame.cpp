// Homed only in the frame it was homed in (home_frame.hpp).
#include "engine.hpp"

namespace homing {

// Run at the start of a period: a change of settings since the last one
// unhomes before anything moves.
void Engine::keep_home_frames(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    if (run.home && *run.home != home_frame(settings.axes[a])) run.home.reset();
    // A stored position is where the axis rested in its frame then.
    if (run.restored && *run.restored != home_frame(settings.axes[a])) run.restored.reset();
  }
}

}  // namespace homing
