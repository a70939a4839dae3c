// A deliberate violation, for the layer check's own test (tests/CMakeLists.txt):
// the register table reaching up into persistence.
#include "homing/settings.hpp"
#include "persistence/settings_store.hpp"
#include "registers/table.hpp"
