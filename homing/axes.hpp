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

constexpr bool is_rotary(std::size_t axis) { return axis >= 3; }
constexpr std::string_view axis_unit(std::size_t axis) { return is_rotary(axis) ? "deg" : "mm"; }
constexpr AxisMask axis_bit(std::size_t axis) { return static_cast<AxisMask>(1u << axis); }
constexpr AxisMask kAllAxes = 0x3F;

}  // namespace homing
