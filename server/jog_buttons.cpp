#include "jog_buttons.hpp"

namespace server {

std::optional<std::int8_t> JogButtons::write(std::size_t axis, std::int8_t direction, bool on, std::uint64_t client) {
  auto& mine = holders(axis, direction);
  if (!on) {
    if (!mine.contains(client)) return std::nullopt;
    mine.clear();
    // Released: the axis stops (a jog runs only in a direction held alone,
    // so whatever runs is this one, or nothing).
    return std::int8_t{0};
  }
  const bool pressed = mine.empty();
  mine.insert(client);
  if (!pressed) return std::nullopt;  // held already: still held, nothing starts
  return held(axis, static_cast<std::int8_t>(-direction)) ? std::int8_t{0} : direction;
}

homing::AxisMask JogButtons::disconnected(std::uint64_t client) {
  homing::AxisMask released = 0;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a)
    for (auto* buttons : {&plus_[a], &minus_[a]})
      if (buttons->contains(client)) {
        buttons->clear();
        released |= homing::axis_bit(a);
      }
  return released;
}

}  // namespace server
