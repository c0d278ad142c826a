// UPA steering vectors against the element-by-element closed form
// exp(j 2 pi r_k . u / lambda), and their orthogonality at DFT directions.
#include "channel/upa.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <complex>
#include <tuple>
#include <vector>

using uavsim::channel::Upa;
using uavsim::channel::UpaConfig;

namespace {

constexpr double kPi = 3.14159265358979323846;

UpaConfig Array(int mx, int my, double d) {
  UpaConfig c;
  c.mx = mx;
  c.my = my;
  c.spacing_wavelengths = d;
  return c;
}

}  // namespace

TEST_CASE("Upa: steering vector is exp(j 2 pi r.u / lambda) element by element", "[channel]") {
  const double lambda_m = 299792458.0 / 28e9;
  for (const auto& [mx, my, d] : {std::tuple{4, 3, 0.5}, std::tuple{4, 3, 0.7},
                                  std::tuple{64, 5, 0.5}, std::tuple{1, 1, 0.5}}) {
    const Upa upa(Array(mx, my, d));
    const double theta = 0.7, phi = 0.4;
    const Eigen::Vector3d u(std::cos(phi) * std::cos(theta), std::cos(phi) * std::sin(theta),
                            std::sin(phi));
    const Eigen::VectorXcd a = upa.Steering(theta, phi);
    REQUIRE(a.size() == mx * my);
    for (int n = 0; n < my; ++n)
      for (int m = 0; m < mx; ++m) {
        // Element (m, n) in metres, array centre at the origin.
        const Eigen::Vector3d r_m(d * lambda_m * (m - (mx - 1) / 2.0),
                                  d * lambda_m * (n - (my - 1) / 2.0), 0.0);
        const std::complex<double> expected = std::polar(1.0, 2.0 * kPi * r_m.dot(u) / lambda_m);
        CHECK(std::abs(a[m + mx * n] - expected) < 1e-12);
      }
    CHECK(a.squaredNorm() == Approx(mx * my).epsilon(1e-12));
  }
}

TEST_CASE("Upa: steering vectors of the DFT directions are orthogonal", "[channel]") {
  const int mx = 8, my = 4;
  const Upa upa(Array(mx, my, 0.5));
  // d u_x = k / Mx, d u_y = l / My: visible directions only (u_x^2 + u_y^2 < 1).
  std::vector<Eigen::VectorXcd> beams;
  for (int k = -mx / 2; k < mx / 2; ++k)
    for (int l = -my / 2; l < my / 2; ++l) {
      const double ux = 2.0 * k / mx, uy = 2.0 * l / my;
      if (ux * ux + uy * uy >= 1.0) continue;
      beams.push_back(upa.Steering(Eigen::Vector3d(ux, uy, std::sqrt(1.0 - ux * ux - uy * uy))));
    }
  REQUIRE(beams.size() >= 10);
  for (std::size_t i = 0; i < beams.size(); ++i)
    for (std::size_t j = 0; j < beams.size(); ++j) {
      const double inner = std::abs(beams[i].dot(beams[j]));
      if (i == j)
        CHECK(inner == Approx(mx * my).epsilon(1e-12));
      else
        CHECK(inner < 1e-9);
    }
}

TEST_CASE("Upa: angles and directions are inverse, theta azimuth, phi elevation", "[channel]") {
  for (const double theta : {-3.0, -1.2, 0.0, 0.5, 2.9})
    for (const double phi : {-1.2, -0.3, 0.0, 0.8, 1.5}) {
      const Eigen::Vector3d u = Upa::Direction(theta, phi);
      CHECK(u.norm() == Approx(1.0).epsilon(1e-14));
      CHECK(u.z() == Approx(std::sin(phi)).margin(1e-14));  // elevation above the panel
      const auto a = Upa::Angles(u);
      CHECK(a.theta_rad == Approx(theta).margin(1e-12));
      CHECK(a.phi_rad == Approx(phi).margin(1e-12));
    }
  // Broadside: phi = pi/2, theta 0 by convention.
  const auto b = Upa::Angles(Eigen::Vector3d(0, 0, 2));
  CHECK(b.phi_rad == Approx(kPi / 2));
  CHECK(b.theta_rad == 0.0);
}

TEST_CASE("Upa: orientation puts z_A on the boresight and x_A horizontal", "[channel]") {
  const Eigen::Matrix3d R = Upa::Orientation(30.0, 20.0);
  const double az = 30.0 * kPi / 180.0, el = 20.0 * kPi / 180.0;
  const Eigen::Vector3d boresight(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                  std::sin(el));
  CHECK((R.col(2) - boresight).norm() < 1e-14);
  CHECK(R.col(0).z() == 0.0);
  CHECK((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-14);
  CHECK(R.determinant() == Approx(1.0));
  // The default: boresight at the zenith.
  const Eigen::Matrix3d up = Upa::Orientation(0.0, 90.0);
  CHECK((up.col(2) - Eigen::Vector3d::UnitZ()).norm() < 1e-14);
  // A world direction along the boresight is broadside in A.
  const Upa upa(Array(8, 8, 0.5), R);
  CHECK((upa.ToArrayFrame(boresight) - Eigen::Vector3d::UnitZ()).norm() < 1e-14);
}
