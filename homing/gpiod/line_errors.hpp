#pragma once
// Start-up error texts, shared by the libgpiod implementation and the test
// fake so that tests see exactly what a technician sees. Each names the
// signal, the chip and the line, and says what to do.
#include <string>

#include "line_api.hpp"

namespace homing::gpiod::errors {

std::string chip_open(const LineSpec& spec, const std::string& chip, int err);
std::string no_offset(const LineSpec& spec, unsigned line_count);
std::string no_name(const LineSpec& spec);
std::string offset_needs_chip(const LineSpec& spec);
std::string busy(const LineSpec& spec, const std::string& user);
std::string request_failed(const LineSpec& spec, int err);

}  // namespace homing::gpiod::errors
