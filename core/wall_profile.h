// Where a run's wall-clock time goes: seconds per named part (a sensor's
// capture, a node's pre-processing, a method at the edge, ...), for users
// (metrics.json's profile_s) and for finding what to speed up.
//
// Wall time is not deterministic: a profile never feeds back into the
// simulation, and outputs that carry it (metrics.json) say so. Parts keep
// the order in which they were first measured. Not thread-safe: measure
// from the thread that runs the event loop.
#pragma once

#include <chrono>
#include <deque>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace uavsim::core {

class WallProfile {
 public:
  // One part's running total; stays valid as long as the profile.
  struct Part {
    std::string name;
    double seconds = 0.0;
  };

  // Adds the wall time between its construction and destruction to a part.
  class Scope {
   public:
    explicit Scope(Part* part)
        : part_(part), start_(part ? std::chrono::steady_clock::now() : Clock::time_point{}) {}
    ~Scope() {
      if (part_) part_->seconds += std::chrono::duration<double>(Clock::now() - start_).count();
    }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    using Clock = std::chrono::steady_clock;
    Part* part_;
    Clock::time_point start_;
  };

  // The part called `name`, created at zero on first use.
  Part& part(const std::string& name);
  // Times a scope into part `name`; a null profile times nothing.
  static Scope Measure(WallProfile* profile, const std::string& name) {
    return Scope(profile ? &profile->part(name) : nullptr);
  }

  // Every part in first-use order.
  std::vector<std::pair<std::string, double>> parts() const;
  // The `n` largest parts, largest first (ties in first-use order).
  std::vector<std::pair<std::string, double>> Top(std::size_t n) const;
  double total_s() const;

 private:
  std::deque<Part> parts_;  // stable addresses
  std::map<std::string, Part*> by_name_;
};

}  // namespace uavsim::core
