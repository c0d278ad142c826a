// Progress of long work on a terminal: percent, rate and ETA on one line of
// stderr, redrawn at most 10 times a second. Silent when stderr is not a
// terminal or when `quiet`.
#pragma once

#include <chrono>
#include <string>

namespace uavsim::core {

class Progress {
 public:
  // `unit` names what `total` counts ("sim s", "points", "epochs").
  Progress(std::string label, double total, std::string unit, bool quiet);
  ~Progress();
  void Update(double done);
  void Finish();  // draws 100 % and ends the line
  bool enabled() const { return enabled_; }

 private:
  void Draw(double done);
  std::string label_, unit_;
  double total_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace uavsim::core
