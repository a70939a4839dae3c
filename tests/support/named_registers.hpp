#pragma once
// Registers by the names of the register table, for tests and the soak tester.
#include <cstdint>
#include <string_view>

#include "registers/table.hpp"

namespace test_support {

// The register with this name; throws (naming it) when there is none.
const registers::Register& reg(std::string_view name);

// Raw value of a length in mm (µm registers).
std::int64_t um(double mm);

}  // namespace test_support
