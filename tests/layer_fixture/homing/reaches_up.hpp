#pragma once
// A deliberate violation, for the layer check's own test (tests/CMakeLists.txt):
// the engine reaching up into the runtime, once from the root and once relatively.
#include <array>

#include "../server/control_loop.hpp"
#include "homing/io.hpp"
#include "server/machine_io.hpp"
