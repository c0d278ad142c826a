#include "pipeline/tracking/gospa.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pipeline/tracking/assignment.h"

namespace uavsim::pipeline {
namespace {

void Check(const GospaConfig& c) {
  if (!(c.c_m > 0.0) || !(c.p >= 1.0))
    throw std::invalid_argument("GOSPA: c_m must be > 0 and p >= 1");
}

// min(d(x_i, y_j), c)^p for every pair.
Eigen::MatrixXd CutCosts(const std::vector<Eigen::Vector3d>& x,
                         const std::vector<Eigen::Vector3d>& y, const GospaConfig& config) {
  Eigen::MatrixXd cost(static_cast<Eigen::Index>(x.size()), static_cast<Eigen::Index>(y.size()));
  for (std::size_t i = 0; i < x.size(); ++i)
    for (std::size_t j = 0; j < y.size(); ++j)
      cost(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          std::pow(std::min((x[i] - y[j]).norm(), config.c_m), config.p);
  return cost;
}

}  // namespace

GospaScore Gospa(const std::vector<Eigen::Vector3d>& truths,
                 const std::vector<Eigen::Vector3d>& estimates, const GospaConfig& config) {
  Check(config);
  // A pair at c or more costs c^p, as leaving both out does (c^p / 2 each):
  // the optimal full assignment of the cut costs is an optimal GOSPA one.
  const Eigen::MatrixXd cost = CutCosts(truths, estimates, config);
  const std::vector<int> match = MinCostAssignment(cost);
  const double half = std::pow(config.c_m, config.p) / 2.0;
  GospaScore s;
  s.estimate_of_truth.assign(truths.size(), -1);
  for (std::size_t i = 0; i < truths.size(); ++i) {
    const int j = match[i];
    if (j >= 0 && (truths[i] - estimates[static_cast<std::size_t>(j)]).norm() < config.c_m) {
      s.estimate_of_truth[i] = j;
      s.localization_m2 += cost(static_cast<Eigen::Index>(i), j);
      ++s.assigned;
    }
  }
  s.missed = static_cast<int>(truths.size()) - s.assigned;
  s.false_targets = static_cast<int>(estimates.size()) - s.assigned;
  s.missed_m2 = half * s.missed;
  s.false_m2 = half * s.false_targets;
  s.gospa_m = std::pow(s.localization_m2 + s.missed_m2 + s.false_m2, 1.0 / config.p);
  return s;
}

double Ospa(const std::vector<Eigen::Vector3d>& truths,
            const std::vector<Eigen::Vector3d>& estimates, const GospaConfig& config) {
  Check(config);
  const std::size_t n = std::max(truths.size(), estimates.size());
  const std::size_t m = std::min(truths.size(), estimates.size());
  if (n == 0) return 0.0;
  const Eigen::MatrixXd cost = CutCosts(truths, estimates, config);
  const std::vector<int> match = MinCostAssignment(cost);
  double sum = std::pow(config.c_m, config.p) * static_cast<double>(n - m);
  for (std::size_t i = 0; i < truths.size(); ++i)
    if (match[i] >= 0) sum += cost(static_cast<Eigen::Index>(i), match[i]);
  return std::pow(sum / static_cast<double>(n), 1.0 / config.p);
}

}  // namespace uavsim::pipeline
