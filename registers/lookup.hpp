#pragma once
// Finding rows of the table by address (what the server gets on the wire) or by
// name (what the SQLite store, homingctl and the tests use).
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "registers/table.hpp"

namespace registers {

// The register whose words (or bit) cover `address`, or nullptr. For a 32-bit
// register both its addresses find it; compare reg->address to tell the halves.
const Register* find_register(Unit unit, Table table, std::uint16_t address);

// The registers with a word (or bit) in [first, first + count), in address
// order: what a read of that range returns, found with two binary searches.
std::span<const Register> registers_overlapping(Unit unit, Table table, std::uint16_t first, std::size_t count);

// By full name ("axis.x.seek_feedrate", "sim.seed"), or nullptr.
const Register* find_register(std::string_view name);

}  // namespace registers
