// Writes (or, with --check, verifies) every generated file of hmi_maps/ from
// the register table, and with --docs the generated parts of docs/ (the
// register reference, the alarm list of the troubleshooting guide and the
// register tables of every guide). Run
// from the repository root:
//   build/bin/gen_hmi_maps --out hmi_maps --docs docs
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "registers/exports.hpp"
#include "registers/exports_docs.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Generate the HMI/SCADA register maps (hmi_maps/) from registers/table.cpp"};
  std::string out_dir = "hmi_maps";
  std::string docs_dir;
  bool check = false;
  app.add_option("--out", out_dir, "directory to write into (default hmi_maps)");
  app.add_option("--docs", docs_dir, "also the generated parts of this docs directory (registers.md, the alarm list "
                                     "of troubleshooting.md, every guide's register tables)");
  app.add_flag("--check", check, "write nothing; exit 1 if a file differs from what would be generated");
  CLI11_PARSE(app, argc, argv);

  namespace fs = std::filesystem;
  int stale = 0;
  // Writes (or compares) one file; false when it cannot be written.
  const auto put = [&](const fs::path& path, const std::string& content) {
    if (check) {
      std::ifstream in(path, std::ios::binary);
      std::stringstream have;
      have << in.rdbuf();
      if (!in || have.str() != content) {
        fmt::print(stderr, "stale: {}\n", path.string());
        ++stale;
      }
      return true;
    }
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << content;
    if (!out) {
      fmt::print(stderr, "cannot write {}\n", path.string());
      return false;
    }
    fmt::print("wrote {}\n", path.string());
    return true;
  };
  for (const auto& file : registers::generate_hmi_maps())
    if (!put(fs::path(out_dir) / file.name, file.content)) return 2;
  if (!docs_dir.empty()) {
    for (const auto& file : registers::generate_doc_files())
      if (!put(fs::path(docs_dir) / file.name, file.content)) return 2;
    for (const auto& section : registers::generate_doc_sections()) {
      const fs::path path = fs::path(docs_dir) / section.file;
      std::ifstream in(path, std::ios::binary);
      std::stringstream have;
      have << in.rdbuf();
      const auto spliced = registers::splice_section(have.str(), section);
      if (!in || !spliced) {
        fmt::print(stderr, "{}: no lines '{}' and '{}' to put the generated {} between\n", path.string(),
                   registers::begin_marker(section.name), registers::end_marker(section.name), section.name);
        return 2;
      }
      if (!put(path, *spliced)) return 2;
    }
    // Every guide's register tables (marker lines naming the registers).
    std::vector<fs::path> guides;
    for (const auto& entry : fs::directory_iterator(docs_dir))
      if (entry.path().extension() == ".md") guides.push_back(entry.path());
    std::sort(guides.begin(), guides.end());
    for (const fs::path& path : guides) {
      std::ifstream in(path, std::ios::binary);
      std::stringstream have;
      have << in.rdbuf();
      const auto doc = registers::splice_register_sections(path.filename().string(), have.str());
      if (!doc.text) {
        fmt::print(stderr, "{}\n", doc.error);
        return 2;
      }
      if (*doc.text != have.str() || check)
        if (!put(path, *doc.text)) return 2;
    }
  }
  if (stale)
    fmt::print(stderr, "{} file(s) stale: run build/bin/gen_hmi_maps --out {}{}\n", stale, out_dir,
               docs_dir.empty() ? "" : " --docs " + docs_dir);
  return stale ? 1 : 0;
}
