#include "pipeline/tracking/assignment.h"

#include <dlib/optimization/max_cost_assignment.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace uavsim::pipeline {

std::vector<int> MinCostAssignment(const Eigen::MatrixXd& cost) {
  const auto rows = static_cast<long>(cost.rows()), cols = static_cast<long>(cost.cols());
  if (!cost.allFinite() || (cost.size() && cost.minCoeff() < 0.0))
    throw std::invalid_argument("MinCostAssignment: costs must be finite and >= 0");
  std::vector<int> out(static_cast<std::size_t>(rows), -1);
  if (rows == 0 || cols == 0) return out;
  // dlib maximises over a square integer matrix: pad with columns or rows
  // of the largest cost (a dummy is the worst real choice, so it changes no
  // real pair) and maximise largest - cost.
  const long n = std::max(rows, cols);
  const double largest = cost.maxCoeff();
  const double scale = largest > 0.0 ? 1e12 / largest : 1.0;
  dlib::matrix<long long> gain(n, n);
  for (long r = 0; r < n; ++r)
    for (long c = 0; c < n; ++c) {
      const double real = r < rows && c < cols ? cost(r, c) : largest;
      gain(r, c) = std::llround((largest - real) * scale);
    }
  const std::vector<long> assigned = dlib::max_cost_assignment(gain);
  for (long r = 0; r < rows; ++r)
    if (assigned[static_cast<std::size_t>(r)] < cols)
      out[static_cast<std::size_t>(r)] = static_cast<int>(assigned[static_cast<std::size_t>(r)]);
  return out;
}

}  // namespace uavsim::pipeline
