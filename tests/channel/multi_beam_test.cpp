// Several targets served at once (channel/multi_beam.h) against the array
// factor: two targets on line-of-sight channels of a zenith-facing 8 x 8
// lambda/2 UPA, each beam's leakage into the other's target the product of
// Dirichlet kernels of their direction difference.
#include "channel/multi_beam.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "channel/beamformer.h"

namespace uavsim::channel {
namespace {

constexpr double kPi = 3.14159265358979323846;

BaseStationConfig LosOnly() {
  BaseStationConfig c;
  c.position_m = {0.0, 0.0, 10.0};
  c.path_model = PathModel::kLosOnly;
  return c;
}

// |a(u_1)^H a(u_2)|^2 / N for the default 8 x 8 zenith-facing array: a
// world direction u has array coordinates (u_y, -u_x, u_z).
double Leakage(const Eigen::Vector3d& bs, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2) {
  const auto dirichlet = [](int m, double x) {
    return std::abs(std::sin(x)) < 1e-12 ? m : std::sin(m * x) / std::sin(x);
  };
  const Eigen::Vector3d u1 = (p1 - bs).normalized(), u2 = (p2 - bs).normalized();
  const double ax = dirichlet(8, kPi * 0.5 * (u1.y() - u2.y()));
  const double ay = dirichlet(8, kPi * 0.5 * (-u1.x() + u2.x()));
  return ax * ax * ay * ay / 64.0;
}

TEST_CASE("MultiBeamScorer: two targets' SINR from the array factor", "[channel]") {
  const BaseStationConfig bs = LosOnly();
  const Eigen::Vector3d t1(20.0, 10.0, 35.0), t2(15.0, 14.0, 32.0);
  const double leak_1 = Leakage(bs.position_m, t1, t2), leak_2 = Leakage(bs.position_m, t2, t1);
  REQUIRE(leak_1 > 0.1);  // close enough in angle that the leakage matters
  REQUIRE(leak_1 < 32.0);
  MultiBeamScorer scorer(bs, 0.0, {"a", "b"}, {"mtt", "ekf"}, {0.0, 20.0},
                         core::RngStream(1, "multi_beam_test"));
  // mtt: beams at both targets (swapped in its list); ekf: one beam, at t2.
  MethodBeams mtt{{t2, t1}, {1, 0}}, ekf{{t2}, {-1, 0}};
  scorer.AddWindow({t1, t2}, {{"mtt", mtt}, {"ekf", ekf}}, FreeSpace());
  for (std::size_t i = 0; i < 2; ++i) {
    const double snr = std::pow(10.0, scorer.snr_db()[i] / 10.0);
    INFO("snr " << scorer.snr_db()[i]);
    // Two beams, half the power each: SINR_k = N / (2 / SNR + leakage).
    const double both =
        std::log2(1.0 + 64.0 / (2.0 / snr + leak_1)) + std::log2(1.0 + 64.0 / (2.0 / snr + leak_2));
    CHECK(scorer.MeanSumRate("perfect", i) == Approx(both).epsilon(1e-9));
    CHECK(scorer.MeanSumRate("mtt", i) == Approx(both).epsilon(1e-9));
    // One beam, the whole power, one target served and no interference.
    CHECK(scorer.MeanSumRate("ekf", i) ==
          Approx(RateBpsHz(scorer.snr_db()[i], 64.0)).epsilon(1e-9));
  }
  // The CSV: per beam set, SNR, target, then the sum.
  std::istringstream csv(scorer.Csv());
  std::string line;
  std::getline(csv, line);
  CHECK(line == "snr_db,beam,target,rate_bps_hz");
  std::getline(csv, line);
  CHECK(line.rfind("0.00,perfect,a,", 0) == 0);
  std::getline(csv, line);
  CHECK(line.rfind("0.00,perfect,b,", 0) == 0);
  std::getline(csv, line);
  CHECK(line.rfind("0.00,perfect,sum,", 0) == 0);
  CHECK_THROWS_AS(scorer.AddWindow({t1}, {}, FreeSpace()), std::invalid_argument);
}

TEST_CASE("MultiBeamGains: one beam and one target is the single-beam gain", "[channel]") {
  const Eigen::VectorXcd h = Eigen::VectorXcd::Constant(4, std::complex<double>(0.5, 0.5));
  const Eigen::VectorXcd f = Eigen::VectorXcd::Constant(4, std::complex<double>(0.5, 0.0));
  const auto g = MultiBeamGains({h}, {f}, {0});
  REQUIRE(g.size() == 1);
  CHECK(g[0].signal == Approx(BeamGain(h, f)));
  CHECK(g[0].interference == 0.0);
  CHECK(SinrRateBpsHz(10.0, 1, g[0]) == Approx(RateBpsHz(10.0, BeamGain(h, f))));
  CHECK(SinrRateBpsHz(10.0, 1, MultiBeamGains({h}, {f}, {-1})[0]) == 0.0);
  CHECK_THROWS_AS(MultiBeamGains({h}, {f}, {1}), std::invalid_argument);
  CHECK_THROWS_AS(MultiBeamGains({h}, {f}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace uavsim::channel
