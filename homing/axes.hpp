#pragma once
// Axis indices and names shared by every layer.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace homing {

inline constexpr std::size_t kAxisCount = 6;
using AxisMask = std::uint8_t;  // bit 0 = X ... bit 5 = C

inline constexpr std::array<std::string_view, kAxisCount> kAxisLetters{"x", "y", "z", "a", "b", "c"};
inline constexpr std::array<char, kAxisCount> kAxisUpper{'X', 'Y', 'Z', 'A', 'B', 'C'};

// A, B, C: rotary by default, and the only axes that may be rotary. What an
// axis is and which unit it shows come from its axis.<a>.kind setting
// (settings.hpp: AxisKind, gantry.hpp: axis_unit), never from this alone.
constexpr bool is_rotary(std::size_t axis) { return axis >= 3; }
constexpr AxisMask axis_bit(std::size_t axis) { return static_cast<AxisMask>(1u << axis); }
constexpr AxisMask kAllAxes = 0x3F;

}  // namespace homing
