// The committed hmi_maps/ must be what the table generates today.
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>

#include "registers/exports.hpp"

namespace {

std::string first_difference(const std::string& have, const std::string& want) {
  std::istringstream a(have), b(want);
  std::string la, lb;
  for (int line = 1;; ++line) {
    const bool ga = static_cast<bool>(std::getline(a, la));
    const bool gb = static_cast<bool>(std::getline(b, lb));
    if (!ga && !gb) return "(line endings differ)";
    if (la != lb || ga != gb)
      return "line " + std::to_string(line) + ":\n  committed: " + (ga ? la : "<end of file>") +
             "\n  generated: " + (gb ? lb : "<end of file>");
  }
}

}  // namespace

TEST_CASE("hmi_maps in the repository are fresh") {
  for (const auto& file : registers::generate_hmi_maps()) {
    const std::string path = std::string(HMI_MAPS_DIR) + "/" + file.name;
    std::ifstream in(path, std::ios::binary);
    std::stringstream have;
    have << in.rdbuf();
    INFO("hmi_maps/" << file.name << " is stale; regenerate with: build/bin/gen_hmi_maps --out hmi_maps\n"
                     << (in ? first_difference(have.str(), file.content) : "file missing"));
    CHECK((in && have.str() == file.content));
  }
}

TEST_CASE("registers.csv has exactly the columns of the contract") {
  const auto files = registers::generate_hmi_maps();
  for (const char* name : {"registers.csv", "sim_registers.csv"}) {
    const auto it = std::find_if(files.begin(), files.end(), [&](const auto& f) { return f.name == name; });
    REQUIRE(it != files.end());
    CHECK(it->content.substr(0, it->content.find('\n')) ==
          "name,table,address,words,type,access,unit,scale,min,max,default,persisted,description");
  }
}
