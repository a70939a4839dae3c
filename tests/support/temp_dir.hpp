#pragma once
// A fresh directory under $TMPDIR, removed with everything in it when the
// object goes (unless keep() was called: the soak tester keeps it for the
// daemon's log when something went wrong).
#include <filesystem>
#include <string>
#include <string_view>

namespace test_support {

class TempDir {
 public:
  explicit TempDir(std::string_view prefix = "homing-test");
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string file(std::string_view name) const { return (path_ / name).string(); }
  void keep() { keep_ = true; }

 private:
  std::filesystem::path path_;
  bool keep_ = false;
};

// The whole file ("" when it cannot be read).
std::string read_file(const std::string& path);
// Replaces the file's contents.
void write_text(const std::string& path, std::string_view text);

}  // namespace test_support
