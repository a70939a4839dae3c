#pragma once
// homingd --export-settings FILE / --import-settings FILE: settings file
// transfer on --db, then exit without serving.
#include "options.hpp"

namespace server {

bool is_settings_file_mode(const Options& opt);
// Exit code: 0 done, 1 refused (the reason on stderr; an import changes nothing then).
int run_settings_file_mode(const Options& opt);

}  // namespace server
