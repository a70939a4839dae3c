#pragma once
// Finding rows of the table by address (what the server gets on the wire) or by
// name (what the SQLite store, homingctl and the tests use).
#include <cstdint>
#include <string_view>

#include "registers/table.hpp"

namespace registers {

// The register whose words (or bit) cover `address`, or nullptr. For a 32-bit
// register both its addresses find it; compare reg->address to tell the halves.
const Register* find_register(Unit unit, Table table, std::uint16_t address);

// By full name ("axis.x.seek_feedrate", "sim.seed"), or nullptr.
const Register* find_register(std::string_view name);

}  // namespace registers
