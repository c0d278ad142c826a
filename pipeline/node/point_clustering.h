// Point selection shared by the LiDAR and radar nodes (paper Sec. IV-A):
// DBSCAN clustering, "keep the largest clusters", and the deterministic
// subsampling that enforces PointObservation::kMaxPoints.
//
// Pure functions of their inputs: no randomness, no global state, the same
// result for the same input on any thread count. Dbscan alone polls
// termination requests (core::Interrupted) as it goes.
#pragma once

#include <cstddef>
#include <vector>

namespace uavsim::pipeline {

struct DbscanClusters {
  static constexpr int kNoise = -1;
  std::vector<int> label;         // per point: cluster id in [0, size.size()), or kNoise
  std::vector<std::size_t> size;  // points per cluster id (core and border)
};

// DBSCAN (Ester et al., KDD 1996) of `count` points of `dims` coordinates,
// row-major in `coordinates` (count * dims floats). A point is core if at
// least `min_points` points (itself included) lie closer than `eps`
// (Euclidean); clusters are the core points' eps-connected components plus
// the border points they reach. Cluster ids follow the order in which each
// cluster's first core point appears; a border point reachable from two
// clusters goes to the first one expanded. Neighbour queries: a nanoflann
// k-d tree. Throws std::invalid_argument if coordinates.size() is not a
// multiple of dims, dims < 1, eps <= 0 or min_points < 1; core::Interrupted
// on a termination request (polled every 4096 neighbour queries).
DbscanClusters Dbscan(const std::vector<float>& coordinates, int dims, double eps, int min_points);

// The ids of the `k` largest clusters, largest first; equal sizes go to the
// lower id. Fewer if there are fewer clusters.
std::vector<int> LargestClusters(const DbscanClusters& clusters, int k);

// The points of the clusters `chosen` (ids, in order): those of the first
// `kept` together, and each further cluster's apart, as index_of[k] for the
// clustered point k (increasing within each group).
struct ChosenPoints {
  std::vector<std::size_t> kept;
  std::vector<std::vector<std::size_t>> further;
};
ChosenPoints PointsOfClusters(const DbscanClusters& clusters, const std::vector<int>& chosen,
                              std::size_t kept, const std::vector<std::size_t>& index_of);

// `max_count` indices of [0, count) spread evenly (floor(i * count /
// max_count)), increasing; all of them if count <= max_count.
std::vector<std::size_t> EvenlySpacedIndices(std::size_t count, std::size_t max_count);

}  // namespace uavsim::pipeline
