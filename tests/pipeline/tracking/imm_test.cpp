#include "pipeline/tracking/imm.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace uavsim::pipeline {
namespace {

using Imm1 = Imm<1>;
using Imm2 = Imm<2>;

// Two 1-D modes: x = (0, 2), P = (1, 4), mu = (0.6, 0.4).
Imm1 TwoScalarModes() {
  Imm1 imm(std::vector<double>{0.6, 0.4});
  imm.modes()[0].x << 0.0;
  imm.modes()[0].P << 1.0;
  imm.modes()[1].x << 2.0;
  imm.modes()[1].P << 4.0;
  return imm;
}

Eigen::MatrixXd TwoStateChain() {
  Eigen::MatrixXd pi(2, 2);
  pi << 0.9, 0.1,  //
      0.2, 0.8;
  return pi;
}

}  // namespace

TEST_CASE("Imm: mixing two 1-D modes matches the hand-worked case", "[pipeline]") {
  Imm1 imm = TwoScalarModes();
  imm.Mix(TwoStateChain());
  // cbar_0 = 0.9 0.6 + 0.2 0.4 = 0.62,  cbar_1 = 0.1 0.6 + 0.8 0.4 = 0.38.
  REQUIRE(imm.probabilities()[0] == Approx(0.62).epsilon(1e-14));
  REQUIRE(imm.probabilities()[1] == Approx(0.38).epsilon(1e-14));
  // Into mode 0: mu_{0|0} = 0.54 / 0.62 = 27/31, mu_{1|0} = 4/31;
  //   x0_0 = (4/31) 2 = 8/31,
  //   P0_0 = 27/31 1 + 4/31 4 + (27/31)(4/31)(0 - 2)^2 = 1765/961.
  CHECK(imm.modes()[0].x(0) == Approx(8.0 / 31.0).epsilon(1e-14));
  CHECK(imm.modes()[0].P(0, 0) == Approx(1765.0 / 961.0).epsilon(1e-14));
  // Into mode 1: mu_{0|1} = 0.06 / 0.38 = 3/19, mu_{1|1} = 16/19;
  //   x0_1 = (16/19) 2 = 32/19,
  //   P0_1 = 3/19 1 + 16/19 4 + (3/19)(16/19) 4 = 1465/361.
  CHECK(imm.modes()[1].x(0) == Approx(32.0 / 19.0).epsilon(1e-14));
  CHECK(imm.modes()[1].P(0, 0) == Approx(1465.0 / 361.0).epsilon(1e-14));
}

TEST_CASE("Imm: mixing takes each source as source_of hands it over", "[pipeline]") {
  // Mode 1 takes mode 0 in at x = 10 (an unequal-dimension mixing would
  // substitute a state): x0_1 = (3/19) 10 + (16/19) 2 = 62/19; mode 0 mixes
  // as before.
  Imm1 imm = TwoScalarModes();
  imm.Mix(TwoStateChain(), [](const std::vector<Imm1::Mode>& prior, std::size_t i, std::size_t j) {
    Imm1::Mode source = prior[i];
    if (i == 0 && j == 1) source.x << 10.0;
    return source;
  });
  CHECK(imm.modes()[0].x(0) == Approx(8.0 / 31.0).epsilon(1e-14));
  CHECK(imm.modes()[1].x(0) == Approx(62.0 / 19.0).epsilon(1e-14));
  // P0_1 = 3/19 1 + 16/19 4 + (3/19)(16/19)(10 - 2)^2 = 67/19 + 3072/361.
  CHECK(imm.modes()[1].P(0, 0) == Approx(67.0 / 19.0 + 3072.0 / 361.0).epsilon(1e-14));
}

TEST_CASE("Imm: mode probabilities from the likelihoods match the hand-worked case", "[pipeline]") {
  Imm1 imm = TwoScalarModes();
  imm.Mix(TwoStateChain());  // mu = (0.62, 0.38)
  SECTION("Lambda = (0.2, 0.05): mu = (0.124, 0.019) / 0.143") {
    imm.UpdateProbabilities({std::log(0.2), std::log(0.05)});
    CHECK(imm.probabilities()[0] == Approx(124.0 / 143.0).epsilon(1e-14));
    CHECK(imm.probabilities()[1] == Approx(19.0 / 143.0).epsilon(1e-14));
  }
  SECTION("likelihoods that underflow as densities: only their ratio counts") {
    // Lambda_1 / Lambda_0 = e^-1: mu_0 = 0.62 / (0.62 + 0.38 / e).
    imm.UpdateProbabilities({-2000.0, -2001.0});
    const double expected = 0.62 / (0.62 + 0.38 * std::exp(-1.0));
    CHECK(imm.probabilities()[0] == Approx(expected).epsilon(1e-14));
    CHECK(imm.probabilities()[1] == Approx(1.0 - expected).epsilon(1e-13));
  }
  SECTION("a mode whose update failed (log Lambda = -inf) gets probability 0") {
    imm.UpdateProbabilities({-std::numeric_limits<double>::infinity(), std::log(0.3)});
    CHECK(imm.probabilities()[0] == 0.0);
    CHECK(imm.probabilities()[1] == 1.0);
  }
  SECTION("no mode with a finite likelihood: the probabilities stay") {
    const std::vector<double> before = imm.probabilities();
    const double inf = std::numeric_limits<double>::infinity();
    imm.UpdateProbabilities({-inf, -inf});
    CHECK(imm.probabilities() == before);
  }
  SECTION("the modes' estimates are the filter's: untouched") {
    const Imm1::Mode before = imm.modes()[1];
    imm.UpdateProbabilities({0.0, 1.0});
    CHECK(imm.modes()[1].x == before.x);
    CHECK(imm.modes()[1].P == before.P);
  }
}

TEST_CASE("Imm: the combined estimate is the mixture's mean and covariance", "[pipeline]") {
  SECTION("1-D: x = 1.5, P = 0.25 1 + 0.75 4 + 0.25 0.75 (0 - 2)^2 = 4") {
    Imm1 imm = TwoScalarModes();
    imm.Reset(imm.modes()[0], {0.25, 0.75});
    imm.modes()[1].x << 2.0;
    imm.modes()[1].P << 4.0;
    const Imm1::Mode m = imm.Combined();
    CHECK(m.x(0) == Approx(1.5).epsilon(1e-15));
    CHECK(m.P(0, 0) == Approx(4.0).epsilon(1e-15));
  }
  SECTION("2-D, three modes: against E[x x^T] - E[x] E[x]^T") {
    Imm2 imm(std::vector<double>{0.5, 0.3, 0.2});
    imm.modes()[0].x << 1.0, -2.0;
    imm.modes()[0].P << 2.0, 0.3, 0.3, 1.0;
    imm.modes()[1].x << 4.0, 0.5;
    imm.modes()[1].P << 0.5, -0.1, -0.1, 3.0;
    imm.modes()[2].x << -1.0, 1.0;
    imm.modes()[2].P << 1.0, 0.0, 0.0, 0.25;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    Eigen::Matrix2d second = Eigen::Matrix2d::Zero();  // E[x x^T]
    for (std::size_t j = 0; j < 3; ++j) {
      const double mu = imm.probabilities()[j];
      const Imm2::Mode& mode = imm.modes()[j];
      mean += mu * mode.x;
      second += mu * (mode.P + mode.x * mode.x.transpose());
    }
    const Imm2::Mode m = imm.Combined();
    // mean = (0.5 + 1.2 - 0.2, -1 + 0.15 + 0.2) = (1.5, -0.65).
    CHECK(m.x(0) == Approx(1.5).epsilon(1e-15));
    CHECK(m.x(1) == Approx(-0.65).epsilon(1e-15));
    const Eigen::Matrix2d expected = second - mean * mean.transpose();
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 2; ++c) CHECK(m.P(r, c) == Approx(expected(r, c)).epsilon(1e-12));
    CHECK(m.P(0, 1) == m.P(1, 0));
  }
}

TEST_CASE("Imm: probabilities stay normalised through mixing and updates", "[pipeline]") {
  // Three modes, a random stochastic matrix and random log-likelihoods
  // (seeded: deterministic) for 1000 cycles.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> log_lambda(-50.0, 5.0);
  Imm1 imm(std::vector<double>{0.2, 0.3, 0.5});
  for (int cycle = 0; cycle < 1000; ++cycle) {
    Eigen::MatrixXd pi(3, 3);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) pi(i, j) = unit(rng) + 1e-3;
      pi.row(i) /= pi.row(i).sum();
    }
    imm.Mix(pi);
    double sum = 0.0;
    for (double mu : imm.probabilities()) sum += mu;
    REQUIRE(sum == Approx(1.0).epsilon(1e-12));
    imm.UpdateProbabilities({log_lambda(rng), log_lambda(rng), log_lambda(rng)});
    sum = 0.0;
    for (double mu : imm.probabilities()) {
      REQUIRE(mu >= 0.0);
      REQUIRE(mu <= 1.0);
      sum += mu;
    }
    REQUIRE(sum == Approx(1.0).epsilon(1e-12));
  }
}

TEST_CASE("Imm: a single mode is left as it is", "[pipeline]") {
  Imm1 imm(std::vector<double>{1.0});
  imm.modes()[0].x << 3.0;
  imm.modes()[0].P << 2.0;
  Eigen::MatrixXd pi(1, 1);
  pi << 1.0;
  imm.Mix(pi);
  imm.UpdateProbabilities({-7.0});
  CHECK(imm.probabilities()[0] == 1.0);
  CHECK(imm.modes()[0].x(0) == 3.0);
  CHECK(imm.modes()[0].P(0, 0) == 2.0);
}

TEST_CASE("Imm: size mismatches throw and name the sizes", "[pipeline]") {
  Imm1 imm = TwoScalarModes();
  CHECK_THROWS_WITH(imm.Mix(Eigen::MatrixXd::Identity(3, 3)),
                    "Imm::Mix: transition matrix is 3x3, expected 2x2");
  CHECK_THROWS_WITH(imm.UpdateProbabilities({0.0}),
                    "Imm::UpdateProbabilities: 1 log-likelihoods for 2 modes");
  CHECK_THROWS_WITH(Imm1(std::vector<double>{}), "Imm: needs at least one mode, got 0");
  CHECK_THROWS_AS(imm.Reset(Imm1::Mode{}, {}), std::invalid_argument);
}

}  // namespace uavsim::pipeline
