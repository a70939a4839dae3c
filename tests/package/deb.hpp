#pragma once
// The package the fixture built (tests/package/build_deb.cmake), unpacked
// into a throw-away directory: files with dpkg-deb -x, control files with
// dpkg-deb -e into <root>/DEBIAN. Paths inside are mapped with in_root().
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "daemon.hpp"

namespace package_test {

using namespace std::chrono_literals;

inline std::string deb_path() {
  std::vector<std::string> debs;
  if (std::filesystem::is_directory(HOMING_DEB_DIR))
    for (const auto& e : std::filesystem::directory_iterator(HOMING_DEB_DIR))
      if (e.path().extension() == ".deb") debs.push_back(e.path().string());
  if (debs.size() != 1)
    throw std::runtime_error(std::string("expected one .deb in ") + HOMING_DEB_DIR + " (built by the ctest fixture "
                             "'package: cpack builds the homingd .deb'), found " + std::to_string(debs.size()));
  return debs[0];
}

// Runs a command; its output, or an exception naming it and its stderr.
inline std::string run_ok(const std::vector<std::string>& argv, std::chrono::milliseconds timeout = 60s) {
  const auto r = e2e::run_program(argv, timeout);
  if (r.code() != 0) {
    std::string cmd;
    for (const auto& a : argv) cmd += a + " ";
    throw std::runtime_error(cmd + "failed (" + std::to_string(r.code()) + "): " + r.err);
  }
  return r.out;
}

class Unpacked {
 public:
  Unpacked() {
    const std::string deb = deb_path();
    run_ok({"dpkg-deb", "-x", deb, root()});
    run_ok({"dpkg-deb", "-e", deb, (dir_.path() / "root" / "DEBIAN").string()});
  }
  std::string root() const { return (dir_.path() / "root").string(); }
  std::string in_root(const std::string& absolute) const { return root() + absolute; }
  std::string control(const std::string& name) const { return e2e::read_file(in_root("/DEBIAN/" + name)); }
  const e2e::TempDir& dir() const { return dir_; }

  // Every file and symlink of the package (not DEBIAN/), as absolute paths.
  std::set<std::string> files() const {
    std::set<std::string> out;
    for (const auto& e : std::filesystem::recursive_directory_iterator(root())) {
      const std::string rel = "/" + std::filesystem::relative(e.path(), root()).string();
      if (rel.starts_with("/DEBIAN")) continue;
      if (!e.is_directory()) out.insert(rel);
    }
    return out;
  }

 private:
  e2e::TempDir dir_;
};

// "Key: value" fields of a control file (continuation lines dropped).
inline std::map<std::string, std::string> control_fields(const std::string& control) {
  std::map<std::string, std::string> out;
  std::istringstream in(control);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == ' ') continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(' '));
    out[line.substr(0, colon)] = value;
  }
  return out;
}

// The package names in a Depends field: "libc6 (>= 2.34), adduser | passwd"
// gives libc6, adduser, passwd (versions and architecture qualifiers dropped).
inline std::set<std::string> depended_packages(const std::string& depends) {
  std::set<std::string> out;
  std::string piece;
  std::istringstream in(depends);
  while (std::getline(in, piece, ',')) {
    std::istringstream alternatives(piece);
    for (std::string alt; std::getline(alternatives, alt, '|');) {
      const auto begin = alt.find_first_not_of(' ');
      if (begin == std::string::npos) continue;
      const auto end = alt.find_first_of(" (:", begin);
      out.insert(alt.substr(begin, end == std::string::npos ? std::string::npos : end - begin));
    }
  }
  return out;
}

// A unit file's keys: section.key -> values (a key may repeat).
using UnitKeys = std::map<std::string, std::vector<std::string>>;
inline UnitKeys parse_unit(const std::string& text) {
  UnitKeys out;
  std::istringstream in(text);
  std::string line, section;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    if (line.front() == '[' && line.back() == ']') {
      section = line.substr(1, line.size() - 2);
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    out[section + "." + line.substr(0, eq)].push_back(line.substr(eq + 1));
  }
  return out;
}

inline std::vector<std::string> words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

}  // namespace package_test
