// The optimal assignment of rows to columns of a cost matrix (the linear
// sum assignment problem), for the multi-target tracker's association and
// the GOSPA metric (pipeline/tracking/gospa.h). Solved by dlib's
// max_cost_assignment (the Hungarian algorithm, Debian's libdlib-dev) on
// integer costs: the real costs are scaled so the largest is 1e12, so the
// assignment is optimal to within (rows + cols) * largest / 1e12 of the
// real optimum. Deterministic.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace uavsim::pipeline {

// cost: R x C, finite and >= 0. Returns for each row its column, or -1
// (when R > C, the rows left over), minimising the sum over assigned rows;
// every row is assigned when R <= C, every column when C <= R. Throws
// std::invalid_argument for a negative or non-finite cost.
std::vector<int> MinCostAssignment(const Eigen::MatrixXd& cost);

}  // namespace uavsim::pipeline
