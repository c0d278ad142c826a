// Multi-target errors between a set of true positions X and a set of
// estimates Y (world ENU metres):
//
//   GOSPA (Rahmathullah, Garcia-Fernandez, Svensson, "Generalized optimal
//   sub-pattern assignment metric", FUSION 2017), alpha = 2:
//     d = ( min over assignments g of  sum_{(i,j) in g} d(x_i, y_j)^p
//           + c^p / 2 (|X| + |Y| - 2 |g|) )^(1/p)
//   where only pairs closer than c are worth assigning; its p-th power
//   splits into localization (the assigned pairs' d^p), missed (c^p / 2 per
//   unassigned truth) and false (c^p / 2 per unassigned estimate).
//
//   OSPA (Schuhmacher, Vo, Vo, IEEE TSP 2008), m = min(|X|, |Y|),
//   n = max(|X|, |Y|) > 0:
//     d = ( (min over assignments of sum min(d, c)^p + c^p (n - m)) / n )^(1/p)
//   0 when both sets are empty.
//
// The assignment is pipeline/tracking/assignment.h's. Pure functions.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace uavsim::pipeline {

struct GospaConfig {
  double c_m = 10.0;  // cut-off distance
  double p = 2.0;     // order, >= 1
};

struct GospaScore {
  double gospa_m = 0.0;          // the metric, metres
  double localization_m2 = 0.0;  // p-th power parts: sum of assigned d^p
  double missed_m2 = 0.0;        // c^p / 2 per missed target
  double false_m2 = 0.0;         // c^p / 2 per false estimate
  int assigned = 0;              // pairs closer than c
  int missed = 0;                // truths left unassigned
  int false_targets = 0;         // estimates left unassigned
  // For each truth the estimate assigned to it (closer than c), or -1.
  std::vector<int> estimate_of_truth;
};

// Throws std::invalid_argument for c_m <= 0 or p < 1.
GospaScore Gospa(const std::vector<Eigen::Vector3d>& truths,
                 const std::vector<Eigen::Vector3d>& estimates, const GospaConfig& config);

double Ospa(const std::vector<Eigen::Vector3d>& truths,
            const std::vector<Eigen::Vector3d>& estimates, const GospaConfig& config);

}  // namespace uavsim::pipeline
