#pragma once
// How long an event loop (server/event_loop.hpp) keeps polling its sockets
// before it goes to sleep, after a turn in which it served something.
//
// Waking a sleeping thread costs more than serving the request it wakes for:
// on the 2-core bench VM about a fifth of one client's round trip. A client
// that sends its next request as soon as it has the answer (an HMI or a PLC
// within its scan, a SCADA poller) would find the loop asleep every time. So
// the loop polls first, for a window that learns from the waits (as Linux's
// haltpoll governor does for idle virtual CPUs): a wait that ended after the
// window but within the longest window doubles it, a longer wait halves it
// (below the first step: no polling), a wait the polling caught keeps it.
// A client that polls every 100 ms therefore costs no polling at all, an
// idle module none, and `--poll-us 0` turns polling off.
#include <chrono>

namespace server {

inline constexpr int kDefaultPollUs = 100;  // --poll-us

class PollWindow {
 public:
  using Micros = std::chrono::microseconds;
  static constexpr Micros kFirstStep{10};  // the window after the first short wait

  explicit PollWindow(Micros longest) : longest_(longest) {}
  // 0: sleep at once.
  Micros window() const { return window_; }
  // After a wait that followed a turn with work: how long it lasted,
  // polling included, and whether the polling caught what ended it.
  void waited(std::chrono::nanoseconds wait, bool caught);

 private:
  Micros longest_;
  Micros window_{0};
};

}  // namespace server
