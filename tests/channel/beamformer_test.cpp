// Beams, codebook and the rate average against closed forms: the half-power
// beamwidth from the array factor, brute-force codeword search, and rate
// means computed by hand.
#include "channel/beamformer.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <complex>
#include <map>
#include <stdexcept>
#include <string>

using uavsim::channel::BaseStationConfig;
using uavsim::channel::BeamChannel;
using uavsim::channel::BeamGain;
using uavsim::channel::DftCodebook;
using uavsim::channel::DownlinkScorer;
using uavsim::channel::FreeSpace;
using uavsim::channel::LosSteeredGain;
using uavsim::channel::PathModel;
using uavsim::channel::RateSnrAccumulator;
using uavsim::channel::SteeredBeam;
using uavsim::channel::Upa;
using uavsim::channel::UpaConfig;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Normalised array factor of an N-element lambda/2 ULA steered at broadside,
// at angle t off broadside: |sum_m exp(j pi m sin t)|^2 / N^2.
double UlaArrayFactor(int n, double t) {
  std::complex<double> s = 0.0;
  for (int m = 0; m < n; ++m) s += std::polar(1.0, kPi * m * std::sin(t));
  return std::norm(s) / (n * n);
}

// Half-power beamwidth (rad) of that ULA: twice the angle where the factor
// falls to 1/2, by bisection between broadside and the first null.
double UlaHalfPowerBeamwidthRad(int n) {
  double lo = 0.0, hi = std::asin(2.0 / n);
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (UlaArrayFactor(n, mid) > 0.5 ? lo : hi) = mid;
  }
  return lo + hi;  // 2 * (lo + hi) / 2
}

BaseStationConfig LosOnly() {
  BaseStationConfig c;
  c.position_m = {0.0, 0.0, 10.0};
  c.path_model = PathModel::kLosOnly;
  return c;
}

}  // namespace

TEST_CASE("Beamformer: half the half-power beamwidth off broadside loses 3 dB", "[channel]") {
  const double hpbw_rad = UlaHalfPowerBeamwidthRad(8);
  CHECK(hpbw_rad == Approx(0.886 * 2.0 / 8.0).epsilon(0.02));  // the textbook 0.886 lambda / (N d)

  const BaseStationConfig bs = LosOnly();  // 8 x 8, lambda/2, boresight at the zenith
  const BeamChannel channel(bs);
  const double range_m = 40.0;
  const Eigen::Vector3d uav = bs.position_m + range_m * Eigen::Vector3d::UnitZ();  // broadside
  const auto h = channel.Realize(uav, FreeSpace());
  const double perfect = BeamGain(h.h, SteeredBeam(channel.upa(), bs.position_m, uav));
  CHECK(perfect == Approx(64.0).epsilon(1e-9));
  // Pointing error of HPBW / 2 in each principal plane (x_A-z_A and y_A-z_A).
  const Eigen::Matrix3d& R = channel.upa().R_WA();
  for (int axis : {0, 1}) {
    const double e = 0.5 * hpbw_rad;
    const Eigen::Vector3d estimate =
        bs.position_m + range_m * (std::sin(e) * R.col(axis) + std::cos(e) * R.col(2));
    const double off = BeamGain(h.h, SteeredBeam(channel.upa(), bs.position_m, estimate));
    const double loss_db = 10.0 * std::log10(perfect / off);
    INFO("axis " << axis << " loss " << loss_db << " dB");
    CHECK(loss_db == Approx(3.0).margin(0.1));
  }
}

TEST_CASE("Beamformer: the DFT codebook picks the codeword nearest the true direction",
          "[channel]") {
  UpaConfig cfg;
  cfg.mx = 8;
  cfg.my = 4;
  const Upa upa(cfg);
  for (const int oversampling : {1, 2, 4}) {
    const DftCodebook book(upa, oversampling);
    REQUIRE(book.size_x() == 8 * oversampling);
    REQUIRE(book.size_y() == 4 * oversampling);
    for (const auto& [theta, phi] :
         {std::pair{0.3, 1.1}, std::pair{-2.0, 0.5}, std::pair{2.7, 0.2}, std::pair{-0.9, 1.45}}) {
      const Eigen::Vector3d u = Upa::Direction(theta, phi);
      const Eigen::VectorXcd a = upa.Steering(u);
      // Every codeword, built here from the DFT formula without wrapping
      // (wrapping changes only a global phase).
      double best_gain = -1.0;
      int best_kx = -1, best_ky = -1;
      for (int kx = 0; kx < book.size_x(); ++kx)
        for (int ky = 0; ky < book.size_y(); ++ky) {
          Eigen::VectorXcd f(32);
          for (int n = 0; n < 4; ++n)
            for (int m = 0; m < 8; ++m)
              f[m + 8 * n] = std::polar(
                  1.0 / std::sqrt(32.0),
                  2.0 * kPi * ((m - 3.5) * kx / book.size_x() + (n - 1.5) * ky / book.size_y()));
          const double g = BeamGain(a, f);
          if (g > best_gain) best_gain = g, best_kx = kx, best_ky = ky;
        }
      const auto pick = book.Best(u);
      INFO("O " << oversampling << " theta " << theta << " phi " << phi);
      CHECK(pick.kx == best_kx);
      CHECK(pick.ky == best_ky);
      CHECK(BeamGain(a, book.Codeword(pick)) == Approx(best_gain).epsilon(1e-12));
      CHECK(book.Codeword(pick).norm() == Approx(1.0).epsilon(1e-14));
    }
  }
  // O = 1, lambda/2: an orthonormal basis.
  const DftCodebook basis(upa, 1);
  Eigen::MatrixXcd F(32, 32);
  for (int kx = 0; kx < 8; ++kx)
    for (int ky = 0; ky < 4; ++ky) F.col(kx + 8 * ky) = basis.Codeword({kx, ky});
  CHECK((F.adjoint() * F - Eigen::MatrixXcd::Identity(32, 32)).norm() < 1e-12);
}

TEST_CASE("Beamformer: SNR grid and rate averages", "[channel]") {
  const auto grid = uavsim::channel::SnrGridDb(-10.0, 30.0, 2.0);
  REQUIRE(grid.size() == 21);
  CHECK(grid.front() == -10.0);
  CHECK(grid.back() == 30.0);
  CHECK(uavsim::channel::SnrGridDb(0.0, 1.0, 0.1).size() == 11);
  CHECK(uavsim::channel::SnrGridDb(0.0, 1.0, 0.3).size() == 4);
  CHECK_THROWS_AS(uavsim::channel::SnrGridDb(1.0, 0.0, 1.0), std::invalid_argument);

  RateSnrAccumulator acc({-10.0, 0.0, 10.0});
  acc.Add("perfect", 64.0);
  acc.Add("perfect", 16.0);
  acc.Add("ekf", 2.0);
  CHECK(acc.windows("perfect") == 2);
  CHECK(acc.windows("none") == 0);
  CHECK(acc.MeanRateBpsHz("perfect", 0) ==
        Approx(0.5 * (std::log2(1.0 + 0.1 * 64.0) + std::log2(1.0 + 0.1 * 16.0))).epsilon(1e-14));
  CHECK(acc.MeanRateBpsHz("perfect", 1) ==
        Approx(0.5 * (std::log2(65.0) + std::log2(17.0))).epsilon(1e-14));
  CHECK(acc.MeanRateBpsHz("perfect", 2) ==
        Approx(0.5 * (std::log2(641.0) + std::log2(161.0))).epsilon(1e-14));
  CHECK(acc.MeanRateBpsHz("ekf", 2) == Approx(std::log2(21.0)).epsilon(1e-14));
  CHECK(acc.MeanGain("perfect") == 40.0);
  CHECK_THROWS_AS(acc.Add("perfect", -1.0), std::invalid_argument);

  RateSnrAccumulator small({0.0});
  small.AddBeam("never");  // registered but without windows: not written
  small.Add("perfect", 1.0);
  small.Add("perfect", 3.0);
  small.Add("ekf", 0.0);
  CHECK(small.Csv() ==
        "snr_db,beam,rate_bps_hz\n"
        "0.00,perfect,1.500000\n"
        "0.00,ekf,0.000000\n");
}

TEST_CASE("DownlinkScorer: one window scores every beam on one channel", "[channel]") {
  BaseStationConfig bs = LosOnly();
  bs.beams = {"steered", "dft"};
  DownlinkScorer scorer(bs, 0.0, {"uavloc", "ekf"}, {0.0, 20.0},
                        uavsim::core::RngStream(1, "downlink"));
  CHECK(scorer.rates().beams() == std::vector<std::string>{"perfect", "uavloc", "ekf",
                                                           "dft_perfect", "dft_uavloc", "dft_ekf"});
  const Eigen::Vector3d truth(20.0, 10.0, 35.0);
  // uavloc is exact; ekf is 5 m off; in the second window ekf has no estimate.
  scorer.AddWindow(truth, {{"uavloc", truth}, {"ekf", truth + Eigen::Vector3d(5.0, 0.0, 0.0)}},
                   FreeSpace());
  scorer.AddWindow(truth, {{"uavloc", truth}}, FreeSpace());
  const auto& r = scorer.rates();
  for (const auto& b : r.beams()) CHECK(r.windows(b) == 2);
  CHECK(r.MeanGain("perfect") == Approx(64.0).epsilon(1e-9));
  CHECK(r.MeanRateBpsHz("perfect", 1) == Approx(std::log2(1.0 + 100.0 * 64.0)).epsilon(1e-9));
  CHECK(r.MeanRateBpsHz("uavloc", 1) == Approx(r.MeanRateBpsHz("perfect", 1)).epsilon(1e-12));
  // ekf: a pointing-error gain in window 1, nothing in window 2.
  const BeamChannel channel(bs);
  const auto h = channel.Realize(truth, FreeSpace());
  const double g_ekf = BeamGain(
      h.h, SteeredBeam(channel.upa(), bs.position_m, truth + Eigen::Vector3d(5.0, 0.0, 0.0)));
  CHECK(g_ekf < 64.0);
  CHECK(r.MeanGain("ekf") == Approx(0.5 * g_ekf).epsilon(1e-9));
  CHECK(r.MeanRateBpsHz("ekf", 1) == Approx(0.5 * std::log2(1.0 + 100.0 * g_ekf)).epsilon(1e-9));
  // The codebook never beats the perfect steered beam.
  CHECK(r.MeanGain("dft_perfect") <= r.MeanGain("perfect") + 1e-9);
  CHECK(r.MeanGain("dft_perfect") > 0.5 * 64.0);

  CHECK_THROWS_AS(scorer.AddWindow(truth, {{"music", truth}}, FreeSpace()), std::invalid_argument);
  CHECK_THROWS_AS(DownlinkScorer(bs, 0.0, {"perfect"}, {0.0}, uavsim::core::RngStream(1, "d")),
                  std::invalid_argument);
  CHECK_THROWS_AS(DownlinkScorer(bs, 0.0, {"ekf", "ekf"}, {0.0}, uavsim::core::RngStream(1, "d")),
                  std::invalid_argument);
}

TEST_CASE("LosSteeredGain: the Dirichlet kernels of the direction error, Mx My on target",
          "[channel]") {
  // A zenith-facing 32 x 32 lambda/2 UPA: x_A = world +y, y_A = world -x
  // (channel/base_station_config.h), so a world direction u has array
  // coordinates (u_y, -u_x, u_z). With f = a(u_e) / sqrt(N) and h = a(u_t):
  //   |h^H f|^2 = |D_Mx(pi d dx)|^2 |D_My(pi d dy)|^2 / N,
  //   D_M(x) = sin(M x) / sin(x), dx, dy the array-coordinate differences.
  BaseStationConfig c = LosOnly();
  c.upa.mx = 32;
  c.upa.my = 32;
  const Upa upa = Upa::FromConfig(c);
  const Eigen::Vector3d bs = c.position_m;
  const auto dirichlet = [](int m, double x) {
    return std::abs(std::sin(x)) < 1e-12 ? m : std::sin(m * x) / std::sin(x);
  };
  const auto closed_form = [&](const Eigen::Vector3d& est, const Eigen::Vector3d& truth) {
    const Eigen::Vector3d ue = (est - bs).normalized(), ut = (truth - bs).normalized();
    const double dx = ue.y() - ut.y(), dy = -ue.x() + ut.x();
    const double ax = dirichlet(32, kPi * 0.5 * dx), ay = dirichlet(32, kPi * 0.5 * dy);
    return ax * ax * ay * ay / 1024.0;
  };
  const Eigen::Vector3d truth(30.0, -20.0, 60.0);
  CHECK(LosSteeredGain(upa, bs, truth, truth) == Approx(1024.0).epsilon(1e-9));
  // Along the ray: the same direction, the same gain.
  CHECK(LosSteeredGain(upa, bs, bs + 2.0 * (truth - bs), truth) == Approx(1024.0).epsilon(1e-9));
  for (const Eigen::Vector3d& error : {Eigen::Vector3d(0.5, 0.0, 0.0), Eigen::Vector3d(0, 2, 0),
                                       Eigen::Vector3d(3, -4, 1), Eigen::Vector3d(-9, 7, -2)}) {
    INFO("error " << error.transpose());
    const double g = LosSteeredGain(upa, bs, truth + error, truth);
    CHECK(g == Approx(closed_form(truth + error, truth)).epsilon(1e-9).margin(1e-9));
    CHECK(g < 1024.0);
  }
}
