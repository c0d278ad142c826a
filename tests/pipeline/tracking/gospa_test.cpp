// GOSPA and OSPA of small configurations computed by hand.
#include "pipeline/tracking/gospa.h"

#include <catch2/catch.hpp>
#include <cmath>

using uavsim::pipeline::Gospa;
using uavsim::pipeline::GospaConfig;
using uavsim::pipeline::Ospa;
using V = Eigen::Vector3d;

TEST_CASE("GOSPA: hand-computed sets (c = 10, p = 2)", "[pipeline]") {
  const GospaConfig c{10.0, 2.0};
  // Both empty: 0.
  CHECK(Gospa({}, {}, c).gospa_m == 0.0);
  // One missed target: c^2 / 2 = 50.
  auto s = Gospa({V(0, 0, 0)}, {}, c);
  CHECK(s.gospa_m == Approx(std::sqrt(50.0)));
  CHECK(s.missed == 1);
  CHECK(s.false_targets == 0);
  // One target, one estimate 3-4-0 away: d = 5, all localization.
  s = Gospa({V(0, 0, 0)}, {V(3, 4, 0)}, c);
  CHECK(s.gospa_m == Approx(5.0));
  CHECK(s.localization_m2 == Approx(25.0));
  CHECK(s.estimate_of_truth == std::vector<int>{0});
  // Beyond the cut-off the pair is a miss and a false target: 50 + 50.
  s = Gospa({V(0, 0, 0)}, {V(30, 0, 0)}, c);
  CHECK(s.gospa_m == Approx(10.0));
  CHECK(s.missed == 1);
  CHECK(s.false_targets == 1);
  CHECK(s.assigned == 0);
  // Two targets, one estimate 1 m from the second: 1 + 50 for the first missed.
  s = Gospa({V(0, 0, 0), V(20, 0, 0)}, {V(21, 0, 0)}, c);
  CHECK(s.gospa_m == Approx(std::sqrt(51.0)));
  CHECK(s.estimate_of_truth == std::vector<int>{-1, 0});
  CHECK(s.missed_m2 == Approx(50.0));
  // The optimal pairing, not the nearest-first: estimates at 1 and 9 with
  // truths at 0 and 8 pair (0,1) and (8,9): 1 + 1 = 2 (not 0-1 left over).
  s = Gospa({V(0, 0, 0), V(8, 0, 0)}, {V(9, 0, 0), V(1, 0, 0)}, c);
  CHECK(s.gospa_m == Approx(std::sqrt(2.0)));
  CHECK(s.estimate_of_truth == std::vector<int>{1, 0});
  // Two false estimates beside one exact: 0 + 2 x 50.
  s = Gospa({V(5, 5, 5)}, {V(5, 5, 5), V(50, 0, 0), V(-50, 0, 0)}, c);
  CHECK(s.gospa_m == Approx(10.0));
  CHECK(s.false_targets == 2);
  CHECK_THROWS_AS(Gospa({}, {}, GospaConfig{0.0, 2.0}), std::invalid_argument);
}

TEST_CASE("OSPA: hand-computed sets (c = 10, p = 2)", "[pipeline]") {
  const GospaConfig c{10.0, 2.0};
  CHECK(Ospa({}, {}, c) == 0.0);
  CHECK(Ospa({V(0, 0, 0)}, {}, c) == Approx(10.0));
  CHECK(Ospa({V(0, 0, 0)}, {V(3, 4, 0)}, c) == Approx(5.0));
  // n = 2, m = 1: (d^2 + c^2) / 2 with d = 1: sqrt(101 / 2).
  CHECK(Ospa({V(0, 0, 0), V(20, 0, 0)}, {V(21, 0, 0)}, c) == Approx(std::sqrt(101.0 / 2.0)));
  // A pair beyond c counts c.
  CHECK(Ospa({V(0, 0, 0)}, {V(30, 0, 0)}, c) == Approx(10.0));
}
