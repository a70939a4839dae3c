#pragma once
// Debounces one digital input from its timed transitions. The accepted edge is
// the first transition of a change that then persisted for the debounce time,
// so bounce delays the decision but never moves the located edge.
namespace homing {

struct AcceptedEdge {
  bool to_level = false;
  double time_s = 0;      // engine time of the first transition
  double position_mm = 0; // motor position at that transition
};

class Debouncer {
 public:
  void reset(bool level, double now_s);
  // One transition at engine time t with the motor at position x.
  void transition(double t_s, double x_mm);
  // End of a period: returns an accepted change, if any.
  bool settle(double now_s, double debounce_s, AcceptedEdge& out);
  bool stable() const { return stable_; }
  bool raw() const { return raw_; }
  // A change is waiting for its debounce time: settle() may accept it later
  // with no new transition, so time alone moves this filter on.
  bool settling() const { return pending_; }
  // Engine time of the last raw transition (or of the reset).
  double last_change_s() const { return last_change_t_; }
  // Raw transitions and accepted changes so far: their difference is the
  // contact's chatter (transitions the debounce time swallowed).
  unsigned long transitions() const { return transitions_; }
  unsigned long accepted() const { return accepted_; }

 private:
  bool stable_ = false;
  bool raw_ = false;
  bool pending_ = false;
  double first_t_ = 0;
  double first_x_ = 0;
  double last_change_t_ = 0;
  unsigned long transitions_ = 0;
  unsigned long accepted_ = 0;
};

}  // namespace homing
