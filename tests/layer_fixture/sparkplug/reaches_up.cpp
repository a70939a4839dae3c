// A deliberate violation, for the layer check's own test (tests/CMakeLists.txt):
// the Sparkplug B payloads reaching up into the runtime.
#include "registers/table.hpp"
#include "server/mqtt_node.hpp"
