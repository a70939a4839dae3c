#pragma once
// Names the calling thread as top, ps -L, perf and /proc/<pid>/task/*/comm
// show it ("control", "tcp-loop-0"...), so a profile or the benchmarks'
// counters can tell homingd's threads apart. Linux keeps 15 characters.
#include <pthread.h>

#include <string>

namespace server {

inline void name_this_thread(const std::string& name) {
  (void)pthread_setname_np(pthread_self(), name.substr(0, 15).c_str());
}

}  // namespace server
