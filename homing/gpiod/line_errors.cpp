#include "line_errors.hpp"

#include <cerrno>
#include <cstring>
#include <fmt/format.h>

namespace homing::gpiod::errors {
namespace {

std::string hint(int err) {
  switch (err) {
    case EACCES:
    case EPERM:
      return "permission denied: run homingd as a user in the 'gpio' group (or give it access to /dev/gpiochip*)";
    case EBUSY:
      return "the line is in use by another program or driver (see 'gpioinfo'); free it or pick another line";
    case ENOENT:
    case ENODEV:
      return "no such GPIO chip (see 'gpiodetect' for the chips this board has)";
    case EINVAL:
      return "the chip refused the request (this line cannot do it, e.g. no edge events or no bias); pick another line";
    default:
      return std::strerror(err);
  }
}

}  // namespace

std::string chip_open(const LineSpec& spec, const std::string& chip, int err) {
  return fmt::format("{}: cannot open GPIO chip '{}': {}", describe(spec), chip, hint(err));
}

std::string no_offset(const LineSpec& spec, unsigned count) {
  return fmt::format("{}: chip '{}' has lines 0..{}, there is no line {}", describe(spec), spec.chip,
                     count == 0 ? 0 : count - 1, std::get<unsigned>(spec.line));
}

std::string no_name(const LineSpec& spec) {
  const std::string& name = std::get<std::string>(spec.line);
  if (spec.chip.empty())
    return fmt::format("{}: no GPIO line is named \"{}\" on any chip (see 'gpioinfo')", describe(spec), name);
  return fmt::format("{}: chip '{}' has no line named \"{}\" (see 'gpioinfo {}')", describe(spec), spec.chip, name,
                     spec.chip);
}

std::string offset_needs_chip(const LineSpec& spec) {
  return describe(spec) + ": a line offset needs a chip (chip = \"gpiochip0\")";
}

std::string busy(const LineSpec& spec, const std::string& user) {
  return fmt::format("{}: the line is in use by '{}'; free it (see 'gpioinfo') or pick another line", describe(spec),
                     user.empty() ? "the kernel" : user);
}

std::string request_failed(const LineSpec& spec, int err) {
  return fmt::format("{}: request failed: {}", describe(spec), hint(err));
}

}  // namespace homing::gpiod::errors
