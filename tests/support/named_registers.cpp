#include "tests/support/named_registers.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "registers/lookup.hpp"

namespace test_support {

const registers::Register& reg(std::string_view name) {
  const registers::Register* r = registers::find_register(name);
  if (!r) throw std::runtime_error("no register named " + std::string(name));
  return *r;
}

std::int64_t um(double mm) { return static_cast<std::int64_t>(std::llround(mm * 1000.0)); }

}  // namespace test_support
