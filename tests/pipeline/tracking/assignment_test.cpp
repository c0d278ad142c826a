// The optimal assignment against brute force over every permutation.
#include "pipeline/tracking/assignment.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <numeric>
#include <random>

using uavsim::pipeline::MinCostAssignment;

namespace {

// The least sum of cost over assignments of min(R, C) pairs, by trying
// every ordering of the longer side.
double BruteForce(const Eigen::MatrixXd& cost) {
  const bool wide = cost.cols() >= cost.rows();
  const Eigen::MatrixXd m = wide ? cost : Eigen::MatrixXd(cost.transpose());
  std::vector<int> cols(static_cast<std::size_t>(m.cols()));
  std::iota(cols.begin(), cols.end(), 0);
  double best = 1e300;
  do {
    double sum = 0.0;
    for (Eigen::Index r = 0; r < m.rows(); ++r) sum += m(r, cols[static_cast<std::size_t>(r)]);
    best = std::min(best, sum);
  } while (std::next_permutation(cols.begin(), cols.end()));
  return best;
}

double CostOf(const Eigen::MatrixXd& cost, const std::vector<int>& a) {
  double sum = 0.0;
  for (std::size_t r = 0; r < a.size(); ++r)
    if (a[r] >= 0) sum += cost(static_cast<Eigen::Index>(r), a[r]);
  return sum;
}

}  // namespace

TEST_CASE("MinCostAssignment: optimal on random square and rectangular matrices", "[pipeline]") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int rows = 1 + trial % 6, cols = 1 + (trial / 6) % 6;
    Eigen::MatrixXd cost(rows, cols);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) cost(r, c) = u(rng);
    if (trial % 5 == 0) cost(0, 0) = 0.0;
    const auto a = MinCostAssignment(cost);
    REQUIRE(a.size() == static_cast<std::size_t>(rows));
    // A one-to-one assignment of min(R, C) pairs.
    std::vector<int> used;
    for (int c : a)
      if (c >= 0) used.push_back(c);
    std::sort(used.begin(), used.end());
    CHECK(std::adjacent_find(used.begin(), used.end()) == used.end());
    CHECK(static_cast<int>(used.size()) == std::min(rows, cols));
    CHECK(CostOf(cost, a) == Approx(BruteForce(cost)).margin(1e-6));
  }
}

TEST_CASE("MinCostAssignment: empty sides and bad costs", "[pipeline]") {
  CHECK(MinCostAssignment(Eigen::MatrixXd(0, 3)).empty());
  CHECK(MinCostAssignment(Eigen::MatrixXd(2, 0)) == std::vector<int>{-1, -1});
  Eigen::MatrixXd zeros = Eigen::MatrixXd::Zero(3, 3);
  const auto a = MinCostAssignment(zeros);
  CHECK(std::count(a.begin(), a.end(), -1) == 0);
  Eigen::MatrixXd bad(1, 1);
  bad(0, 0) = -1.0;
  CHECK_THROWS_AS(MinCostAssignment(bad), std::invalid_argument);
  bad(0, 0) = std::nan("");
  CHECK_THROWS_AS(MinCostAssignment(bad), std::invalid_argument);
}
