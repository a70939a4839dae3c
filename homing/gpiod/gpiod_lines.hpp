#pragma once
// LineApi over libgpiod v1 (Debian 12: libgpiod 1.6). Chips are opened once
// and shared by their lines; everything is released (lines first, then
// chips) when this object dies, so the kernel frees the lines even when the
// daemon exits on an error.
#include <memory>
#include <string>
#include <vector>

#include "line_api.hpp"

struct gpiod_chip;
struct gpiod_line;

namespace homing::gpiod {

class GpiodLines final : public LineApi {
 public:
  explicit GpiodLines(std::string consumer = "homingd");
  ~GpiodLines() override;
  GpiodLines(const GpiodLines&) = delete;
  GpiodLines& operator=(const GpiodLines&) = delete;

  std::expected<LineId, std::string> request_output(const LineSpec& spec, bool initial) override;
  std::expected<LineId, std::string> request_input(const LineSpec& spec) override;
  std::expected<LineId, std::string> request_input_events(const LineSpec& spec) override;
  std::expected<void, std::string> set_value(LineId line, bool value) override;
  std::expected<bool, std::string> get_value(LineId line) override;
  std::expected<std::size_t, std::string> read_events(LineId line, std::span<LineEvent> out) override;
  int event_fd(LineId line) override;

 private:
  struct ChipDeleter {
    void operator()(gpiod_chip* chip) const;
  };
  using ChipPtr = std::unique_ptr<gpiod_chip, ChipDeleter>;
  struct Chip {
    std::string key;  // as written in the config
    ChipPtr handle;
  };
  struct Line {
    LineSpec spec;
    gpiod_line* handle = nullptr;  // owned by its chip; released in the destructor
    bool events = false;           // requested for both edges' events
  };
  enum class Kind { output, input, events };

  std::expected<LineId, std::string> request(const LineSpec& spec, Kind kind, bool initial);
  std::expected<gpiod_line*, std::string> find_line(const LineSpec& spec);
  std::expected<gpiod_chip*, std::string> open_chip(const LineSpec& spec, const std::string& key);

  std::string consumer_;
  std::vector<Chip> chips_;
  std::vector<Line> lines_;
};

}  // namespace homing::gpiod
