#include "pipeline/node/point_clustering.h"

#include <algorithm>
#include <cstdint>
#include <nanoflann.hpp>
#include <numeric>
#include <stdexcept>
#include <utility>

#include "core/interrupt.h"

namespace uavsim::pipeline {
namespace {

// nanoflann's dataset interface over the flat row-major array.
struct FlatCloud {
  const float* data;
  std::size_t count;
  std::size_t dims;
  std::size_t kdtree_get_point_count() const { return count; }
  float kdtree_get_pt(std::size_t i, std::size_t d) const { return data[i * dims + d]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, FlatCloud>,
                                                   FlatCloud, -1, std::uint32_t>;

constexpr int kUnvisited = -2;

}  // namespace

DbscanClusters Dbscan(const std::vector<float>& coordinates, int dims, double eps, int min_points) {
  if (dims < 1) throw std::invalid_argument("Dbscan: dims must be at least 1");
  if (coordinates.size() % static_cast<std::size_t>(dims) != 0)
    throw std::invalid_argument("Dbscan: coordinates.size() is not a multiple of dims");
  if (!(eps > 0.0)) throw std::invalid_argument("Dbscan: eps must be positive");
  if (min_points < 1) throw std::invalid_argument("Dbscan: min_points must be at least 1");

  const std::size_t n = coordinates.size() / static_cast<std::size_t>(dims);
  DbscanClusters out;
  out.label.assign(n, kUnvisited);
  if (n == 0) return out;

  const FlatCloud cloud{coordinates.data(), n, static_cast<std::size_t>(dims)};
  const KdTree tree(dims, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  // L2_Simple compares squared distances; nanoflann's radius test is strict.
  const float eps_sq = static_cast<float>(eps * eps);
  // Unsorted results: the order is still a pure function of the input, and
  // sorting every neighbourhood would cost more than the clustering.
  const nanoflann::SearchParams params(32, 0.0f, false);
  std::vector<std::pair<std::uint32_t, float>> neighbours;
  std::vector<std::uint32_t> frontier;

  // Termination requests are polled every 4096 neighbourhood searches.
  std::size_t searches = 0;
  auto search = [&](std::size_t point) {
    if (++searches % 4096 == 0) core::ThrowIfInterrupted();
    tree.radiusSearch(&coordinates[point * dims], eps_sq, neighbours, params);
  };

  for (std::size_t i = 0; i < n; ++i) {
    if (out.label[i] != kUnvisited) continue;
    search(i);
    if (neighbours.size() < static_cast<std::size_t>(min_points)) {
      out.label[i] = DbscanClusters::kNoise;  // may still become a border point later
      continue;
    }
    const int id = static_cast<int>(out.size.size());
    out.size.push_back(0);
    out.label[i] = id;
    ++out.size[id];
    frontier.clear();
    for (const auto& [j, d2] : neighbours) frontier.push_back(j);
    for (std::size_t k = 0; k < frontier.size(); ++k) {
      const std::uint32_t q = frontier[k];
      if (out.label[q] == DbscanClusters::kNoise) {
        out.label[q] = id;  // border point: reached, but not expanded
        ++out.size[id];
        continue;
      }
      if (out.label[q] != kUnvisited) continue;
      out.label[q] = id;
      ++out.size[id];
      search(q);
      if (neighbours.size() >= static_cast<std::size_t>(min_points))
        for (const auto& [j, d2] : neighbours)
          if (out.label[j] == kUnvisited || out.label[j] == DbscanClusters::kNoise)
            frontier.push_back(j);
    }
  }
  return out;
}

std::vector<int> LargestClusters(const DbscanClusters& clusters, int k) {
  std::vector<int> ids(clusters.size.size());
  std::iota(ids.begin(), ids.end(), 0);
  // stable_sort keeps equal sizes in id order.
  std::stable_sort(ids.begin(), ids.end(),
                   [&](int a, int b) { return clusters.size[a] > clusters.size[b]; });
  if (k >= 0 && static_cast<std::size_t>(k) < ids.size()) ids.resize(k);
  return ids;
}

std::vector<std::size_t> EvenlySpacedIndices(std::size_t count, std::size_t max_count) {
  std::vector<std::size_t> idx;
  if (count <= max_count) {
    idx.resize(count);
    std::iota(idx.begin(), idx.end(), std::size_t{0});
    return idx;
  }
  idx.reserve(max_count);
  // count * i fits easily: clouds are far below 2^32 points.
  for (std::size_t i = 0; i < max_count; ++i) idx.push_back(i * count / max_count);
  return idx;
}

ChosenPoints PointsOfClusters(const DbscanClusters& clusters, const std::vector<int>& chosen,
                              std::size_t kept, const std::vector<std::size_t>& index_of) {
  // 1: a kept cluster; 2 + i: the i-th further one.
  std::vector<std::size_t> role(clusters.size.size(), 0);
  kept = std::min(kept, chosen.size());
  for (std::size_t r = 0; r < chosen.size(); ++r)
    role[static_cast<std::size_t>(chosen[r])] = r < kept ? 1 : 2 + (r - kept);
  ChosenPoints out;
  out.further.resize(chosen.size() - kept);
  for (std::size_t k = 0; k < index_of.size(); ++k) {
    const int id = clusters.label[k];
    if (id == DbscanClusters::kNoise || role[static_cast<std::size_t>(id)] == 0) continue;
    const std::size_t r = role[static_cast<std::size_t>(id)];
    (r == 1 ? out.kept : out.further[r - 2]).push_back(index_of[k]);
  }
  return out;
}

}  // namespace uavsim::pipeline
