#include "maps.hpp"

#include <fmt/format.h>

#include <filesystem>

namespace homingctl {

registers::MapUnits map_units_of(const RawMap& values, const std::string& source) {
  return registers::MapUnits{registers::kinds_of(settings_of(values)), source};
}

std::expected<std::size_t, std::string> write_maps(const std::string& dir, const registers::MapUnits& units) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return std::unexpected(fmt::format("cannot create {}: {}", dir, ec.message()));
  std::size_t n = 0;
  for (const auto& file : registers::generate_hmi_maps(units)) {
    const std::string path = (std::filesystem::path(dir) / file.name).string();
    if (auto w = write_file_atomically(path, file.content); !w) return std::unexpected(w.error());
    ++n;
  }
  return n;
}

}  // namespace homingctl
