// The two protocols of `uavsim train --split` (apps/train/train.h): by trajectory,
// no episode in two parts; by frame, every window of every episode in
// exactly one part, at the stated fractions.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstddef>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "apps/train/train.h"
#include "pipeline/training/dataset.h"

namespace {

using uavsim::pipeline::DataSplit;
using uavsim::pipeline::Episode;

std::vector<Episode> Episodes(int n, int windows) {
  std::vector<Episode> out;
  for (int e = 0; e < n; ++e) {
    Episode ep;
    ep.label = "flight " + std::to_string(e);
    for (int k = 0; k < windows; ++k) ep.window_truth.emplace_back(e, k, 0.0);
    uavsim::pipeline::Sample s;
    s.t_s = 0.1 * e;
    ep.samples.push_back(s);
    out.push_back(ep);
  }
  return out;
}

}  // namespace

TEST_CASE("Split by trajectory: each flight in one part only, 70/15/15", "[sim][train]") {
  const auto d = uavsim::sim::SplitByTrajectory(Episodes(20, 10), 7);
  CHECK(d.split == DataSplit::kTrajectory);
  CHECK(d.train.size() == 14);
  CHECK(d.validation.size() == 3);
  CHECK(d.test.size() == 3);
  std::map<std::string, int> seen;
  for (const auto* part : {&d.train, &d.validation, &d.test})
    for (const Episode& e : *part) {
      ++seen[e.label];
      CHECK(e.scored_windows.empty());  // every window of the flight is this part's
    }
  CHECK(seen.size() == 20);
  for (const auto& [label, count] : seen) {
    INFO(label);
    CHECK(count == 1);
  }
}

TEST_CASE("TrajectoryParts names the part SplitByTrajectory puts each flight in", "[sim][train]") {
  for (const std::uint64_t seed : {1u, 7u, 1234u}) {
    const std::vector<Episode> all = Episodes(23, 10);
    const std::vector<int> part = uavsim::sim::TrajectoryParts(all.size(), seed);
    const auto d = uavsim::sim::SplitByTrajectory(all, seed);
    std::map<std::string, int> expected;
    for (const Episode& e : d.train) expected[e.label] = 0;
    for (const Episode& e : d.validation) expected[e.label] = 1;
    for (const Episode& e : d.test) expected[e.label] = 2;
    REQUIRE(part.size() == all.size());
    for (std::size_t i = 0; i < all.size(); ++i) {
      INFO("seed " << seed << ", episode " << i);
      CHECK(part[i] == expected.at(all[i].label));
    }
  }
  CHECK(uavsim::sim::TrajectoryParts(2, 1) == std::vector<int>{0, 0});  // too few to hold out
}

TEST_CASE("Split by frame: every window in exactly one part, about 70/15/15, seeded",
          "[sim][train]") {
  const int n = 6, windows = 200;
  const auto d = uavsim::sim::SplitByFrame(Episodes(n, windows), 3);
  CHECK(d.split == DataSplit::kFrame);
  // Every flight in every part, in the same order, with its samples.
  for (const auto* part : {&d.train, &d.validation, &d.test}) {
    REQUIRE(part->size() == static_cast<std::size_t>(n));
    for (int e = 0; e < n; ++e) {
      CHECK((*part)[static_cast<std::size_t>(e)].label == "flight " + std::to_string(e));
      CHECK((*part)[static_cast<std::size_t>(e)].samples.size() == 1);
      CHECK((*part)[static_cast<std::size_t>(e)].scored_windows.size() ==
            static_cast<std::size_t>(windows));
    }
  }
  std::size_t count[3] = {0, 0, 0};
  for (std::size_t e = 0; e < static_cast<std::size_t>(n); ++e)
    for (std::size_t k = 0; k < static_cast<std::size_t>(windows); ++k) {
      const int in = d.train[e].scored_windows[k] + d.validation[e].scored_windows[k] +
                     d.test[e].scored_windows[k];
      REQUIRE(in == 1);
      count[0] += d.train[e].scored_windows[k];
      count[1] += d.validation[e].scored_windows[k];
      count[2] += d.test[e].scored_windows[k];
      CHECK(d.train[e].Scored(static_cast<std::int64_t>(k) + 1) ==
            (d.train[e].scored_windows[k] == 1));
    }
  // Binomial fractions of 1 200 windows: within 4 standard deviations.
  const double total = n * windows;
  for (const auto& [part, p] : {std::pair{0, 0.70}, std::pair{1, 0.15}, std::pair{2, 0.15}}) {
    INFO("part " << part);
    CHECK(std::abs(count[part] / total - p) < 4.0 * std::sqrt(p * (1 - p) / total));
  }
  // Neighbouring windows of one flight land in different parts: the split
  // shares flights across parts by design.
  std::set<std::string> test_flights, train_flights;
  for (const Episode& e : d.test)
    for (std::uint8_t s : e.scored_windows)
      if (s) test_flights.insert(e.label);
  for (const Episode& e : d.train)
    for (std::uint8_t s : e.scored_windows)
      if (s) train_flights.insert(e.label);
  CHECK(test_flights == train_flights);
  // The same seed draws the same windows; another seed others.
  const auto again = uavsim::sim::SplitByFrame(Episodes(n, windows), 3);
  const auto other = uavsim::sim::SplitByFrame(Episodes(n, windows), 4);
  CHECK(again.test[2].scored_windows == d.test[2].scored_windows);
  CHECK(other.test[2].scored_windows != d.test[2].scored_windows);
  // Too few windows to train on is refused.
  CHECK_THROWS_AS(uavsim::sim::SplitByFrame(Episodes(1, 0), 3), std::invalid_argument);
}

TEST_CASE("Split by frame: the three copies of a flight share its samples until one changes",
          "[sim][train]") {
  auto d = uavsim::sim::SplitByFrame(Episodes(6, 10), 3);
  REQUIRE(d.train.size() == 6);
  for (std::size_t i = 0; i < d.train.size(); ++i) {
    CHECK(d.train[i].samples.SharesWith(d.validation[i].samples));
    CHECK(d.train[i].samples.SharesWith(d.test[i].samples));
  }
  // Reading through const copies keeps the sharing; writing to one copy
  // gives it its own samples and leaves the others as they were.
  const Episode& train = d.train[2];
  const Episode& validation = d.validation[2];
  const Episode& test = d.test[2];
  const double t = test.samples.front().t_s;
  CHECK(validation.samples.front().t_s == t);
  for (const auto& s : train.samples) CHECK(s.t_s == t);
  CHECK(train.samples.SharesWith(test.samples));
  d.train[2].samples[0].t_s = t + 1.0;
  CHECK_FALSE(train.samples.SharesWith(validation.samples));
  CHECK(validation.samples.SharesWith(test.samples));
  CHECK(validation.samples.front().t_s == t);
  CHECK(train.samples.front().t_s == t + 1.0);
  d.test[3].samples.push_back(Episodes(1, 1).front().samples.front());
  CHECK(std::as_const(d.test[3]).samples.size() == 2);
  CHECK(std::as_const(d.validation[3]).samples.size() == 1);
}
