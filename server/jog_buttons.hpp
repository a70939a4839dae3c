#pragma once
// The jog coils as buttons that several clients may hold (a PLC, a panel, a
// PLC reconnected while its old connection still lingers). A coil reads 1
// while any client holds it. A press is a 1 written while nobody holds that
// button: it starts the jog, or stops the axis when the other direction is
// held too (two buttons pressed on a pendant). A 1 written to a button held
// already joins its holders and starts nothing. A 0 from any holder releases
// the button for all (the jog stops at once, whoever pressed), as does a
// holder's disconnect; a 0 from a client that never held it changes nothing
// (a panel rewriting its coil word cyclically). Pure: no lock, no loop.
#include <array>
#include <cstdint>
#include <optional>
#include <set>

#include "homing/axes.hpp"

namespace server {

class JogButtons {
 public:
  // A jog coil of `axis` (direction +1 or -1) written `on` by `client`: the
  // jog the axis must get now (+1, -1 or 0 to stop), nullopt when unchanged.
  std::optional<std::int8_t> write(std::size_t axis, std::int8_t direction, bool on, std::uint64_t client);
  // Every button `client` holds is released: the axes whose jog must stop.
  homing::AxisMask disconnected(std::uint64_t client);
  // The coil's readback: someone holds it.
  bool held(std::size_t axis, std::int8_t direction) const { return !holders(axis, direction).empty(); }

 private:
  std::set<std::uint64_t>& holders(std::size_t axis, std::int8_t direction) {
    return direction > 0 ? plus_[axis] : minus_[axis];
  }
  const std::set<std::uint64_t>& holders(std::size_t axis, std::int8_t direction) const {
    return direction > 0 ? plus_[axis] : minus_[axis];
  }
  std::array<std::set<std::uint64_t>, homing::kAxisCount> plus_{};
  std::array<std::set<std::uint64_t>, homing::kAxisCount> minus_{};
};

}  // namespace server
