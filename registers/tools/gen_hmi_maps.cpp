// Writes (or, with --check, verifies) every generated file of hmi_maps/ from
// the register table. Run from the repository root:
//   build/bin/gen_hmi_maps --out hmi_maps
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "registers/exports.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Generate the HMI/SCADA register maps (hmi_maps/) from registers/table.cpp"};
  std::string out_dir = "hmi_maps";
  bool check = false;
  app.add_option("--out", out_dir, "directory to write into (default hmi_maps)");
  app.add_flag("--check", check, "write nothing; exit 1 if a file differs from what would be generated");
  CLI11_PARSE(app, argc, argv);

  namespace fs = std::filesystem;
  int stale = 0;
  for (const auto& file : registers::generate_hmi_maps()) {
    const fs::path path = fs::path(out_dir) / file.name;
    if (check) {
      std::ifstream in(path, std::ios::binary);
      std::stringstream have;
      have << in.rdbuf();
      if (!in || have.str() != file.content) {
        fmt::print(stderr, "stale: {}\n", path.string());
        ++stale;
      }
      continue;
    }
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << file.content;
    if (!out) {
      fmt::print(stderr, "cannot write {}\n", path.string());
      return 2;
    }
    fmt::print("wrote {}\n", path.string());
  }
  if (stale) fmt::print(stderr, "{} file(s) stale: run build/bin/gen_hmi_maps --out {}\n", stale, out_dir);
  return stale ? 1 : 0;
}
