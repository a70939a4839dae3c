#pragma once
// The HMI tag files (every file of hmi_maps/) of one configured machine: each
// axis's values in the unit of the kind it moves with (axis.<a>.kind, a slave
// its master's). The committed hmi_maps/ are a new module's.
#include <cstddef>
#include <expected>
#include <string>

#include "registers/exports.hpp"
#include "settings_io.hpp"

namespace homingctl {

// The units of the machine whose settings are `values` (name -> raw; a
// setting missing has its default); `source` says where they came from.
registers::MapUnits map_units_of(const RawMap& values, const std::string& source);

// Writes every file into `dir` (created if missing); the number written, or why not.
std::expected<std::size_t, std::string> write_maps(const std::string& dir, const registers::MapUnits& units);

}  // namespace homingctl
