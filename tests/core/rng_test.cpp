#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "core/rng.h"

using uavsim::core::RngStream;

TEST_CASE("RngStream: same seed and id give the same numbers", "[core]") {
  RngStream a(42, "node/cam1/clock"), b(42, "node/cam1/clock");
  for (int i = 0; i < 1000; ++i) REQUIRE(a.NextU64() == b.NextU64());
}

TEST_CASE("RngStream: a stream does not depend on which other streams exist", "[core]") {
  RngStream alone(7, "lidar1");
  std::vector<std::uint64_t> expected;
  for (int i = 0; i < 100; ++i) expected.push_back(alone.NextU64());
  // Create and use other streams first, as a scenario with an extra sensor would.
  RngStream other(7, "cam2");
  for (int i = 0; i < 1000; ++i) other.NextU64();
  RngStream again(7, "lidar1");
  for (int i = 0; i < 100; ++i) REQUIRE(again.NextU64() == expected[i]);
}

TEST_CASE("RngStream: different ids, seeds and sub-streams differ", "[core]") {
  RngStream a(1, "a"), b(1, "b"), c(2, "a");
  const auto x = a.NextU64(), y = b.NextU64(), z = c.NextU64();
  CHECK(x != y);
  CHECK(x != z);
  RngStream d1 = RngStream(1, "a").Derive("frame/1"), d2 = RngStream(1, "a").Derive("frame/2");
  CHECK(d1.NextU64() != d2.NextU64());
}

TEST_CASE("RngStream: moments of the distributions match their closed forms", "[core]") {
  RngStream r(2024, "stats");
  const int n = 400000;
  double su = 0, su2 = 0, sn = 0, sn2 = 0, se = 0;
  for (int i = 0; i < n; ++i) {
    const double u = r.Uniform();
    REQUIRE(u >= 0.0);
    REQUIRE(u < 1.0);
    su += u, su2 += u * u;
    const double g = r.Normal(3.0, 2.0);
    sn += g, sn2 += g * g;
    se += r.Exponential(0.5);
  }
  const double mu = su / n, vu = su2 / n - mu * mu;
  const double mn = sn / n, vn = sn2 / n - mn * mn;
  // 5-sigma bounds from the standard errors.
  CHECK(std::abs(mu - 0.5) < 5 * std::sqrt(1.0 / 12 / n));
  CHECK(std::abs(vu - 1.0 / 12) < 5 * std::sqrt(1.0 / 180 / n));
  CHECK(std::abs(mn - 3.0) < 5 * 2.0 / std::sqrt(n));
  CHECK(std::abs(std::sqrt(vn) - 2.0) < 5 * 2.0 / std::sqrt(2.0 * n));
  CHECK(std::abs(se / n - 0.5) < 5 * 0.5 / std::sqrt(n));
}

TEST_CASE("RngStream: UniformInt is unbiased (chi-square over 7 bins)", "[core]") {
  RngStream r(5, "ints");
  const int n = 70000;
  std::vector<int> bins(7, 0);
  for (int i = 0; i < n; ++i) ++bins[r.UniformInt(7)];
  double chi2 = 0;
  for (int b : bins) chi2 += (b - n / 7.0) * (b - n / 7.0) / (n / 7.0);
  CHECK(chi2 < 22.46);  // the 0.999 quantile of chi-square with 6 degrees of freedom
}

TEST_CASE("RngStream: Pareto tail follows (scale/x)^shape", "[core]") {
  RngStream r(9, "pareto");
  const int n = 200000;
  int above = 0;
  for (int i = 0; i < n; ++i) {
    const double x = r.Pareto(2.0, 3.0);
    REQUIRE(x >= 2.0);
    above += x > 4.0;
  }
  const double p = 1.0 / 8.0;  // (2/4)^3
  CHECK(std::abs(above / double(n) - p) < 5 * std::sqrt(p * (1 - p) / n));
}
