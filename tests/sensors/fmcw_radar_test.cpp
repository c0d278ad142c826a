// FMCW radar scatterers and IF-cube synthesis against closed forms: the
// header's signal model written out again here sample by sample, the radar
// equation's 40 log10 R, kTBF noise, plane and box geometry, projected-area
// RCS, ITU-R P.838-3 rain attenuation (core/rain_attenuation.h and the
// uplink's rain loss at the same carrier as the oracles), the rain clutter's
// eta law, ground multipath, determinism and config errors. Expected values
// never come from the model's own output.
#include "sensors/fmcw_radar.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <catch2/catch.hpp>

#include <cmath>
#include <complex>
#include <cstring>
#include <functional>
#include <string>
#include <vector>
#include "test_support.h"

#include "channel/uplink.h"
#include "core/error.h"
#include "core/json_io.h"
#include "core/rain_attenuation.h"
#include "core/simulator.h"

using uavsim::core::Material;
using uavsim::core::RadarClass;
using uavsim::core::RngStream;
using uavsim::core::TriangleMesh;
using uavsim::core::WeatherConfig;
using uavsim::core::WorldGeometry;
using uavsim::sensors::FmcwRadar;
using uavsim::sensors::FmcwRadarConfig;
using uavsim::sensors::RadarCube;
using uavsim::sensors::RadarSurfaceConfig;
using uavsim::sensors::RaycastScene;
using uavsim::sensors::Scatterer;

using uavsim::testing::BoxMesh;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kC = 299792458.0;
constexpr double kBoltzmann = 1.380649e-23;

// The default radar at `position`, rpy in degrees, without thermal noise.
FmcwRadarConfig Quiet(const Eigen::Vector3d& position = Eigen::Vector3d::Zero(),
                      const Eigen::Vector3d& rpy_deg = Eigen::Vector3d::Zero()) {
  FmcwRadarConfig c;
  c.pose.position_m = position;
  c.pose.rpy_deg = rpy_deg;
  c.thermal_noise = false;
  return c;
}

// The radar equation per sample, independently: P_t G^2 lambda^2 sigma /
// ((4 pi)^3 R^4) over k T0 fs F, for the default waveform.
double ExpectedSnr(const FmcwRadarConfig& c, double rcs_m2, double range_m) {
  const double lambda = kC / (c.carrier_ghz * 1e9);
  const double pt_w = 1e-3 * std::pow(10.0, c.tx_power_dbm / 10.0);
  const double g = std::pow(10.0, c.antenna_gain_dbi / 10.0);
  const double noise_w =
      kBoltzmann * 290.0 * c.sample_rate_msps * 1e6 * std::pow(10.0, c.noise_figure_db / 10.0);
  return pt_w * g * g * lambda * lambda * rcs_m2 /
         (std::pow(4.0 * kPi, 3) * std::pow(range_m, 4) * noise_w);
}

double MeanPower(const RadarCube& cube) {
  double sum = 0.0;
  for (const auto& x : cube.data) sum += std::norm(std::complex<double>(x));
  return sum / static_cast<double>(cube.data.size());
}

RadarCube SynthesizeOne(const FmcwRadarConfig& c, const std::vector<Scatterer>& s,
                        const WeatherConfig& weather = {}, std::uint64_t seed = 7) {
  WorldGeometry empty;
  RaycastScene scene(empty);
  FmcwRadar radar(c, scene);
  RngStream noise(seed, "radar1");
  return radar.Synthesize(s, weather, noise);
}

Scatterer PointAt(const Eigen::Vector3d& p, double rcs_m2,
                  const Eigen::Vector3d& v = Eigen::Vector3d::Zero()) {
  Scatterer s;
  s.position_m = p;
  s.velocity_mps = v;
  s.rcs_m2 = rcs_m2;
  return s;
}

double TotalRcs(const std::vector<Scatterer>& s, int object) {
  double sum = 0.0;
  for (const Scatterer& x : s)
    if (x.object == object && !x.multipath) sum += x.rcs_m2;
  return sum;
}

// A moving-object world: `mesh` carried by X_WO(t) in an otherwise empty scene.
struct MovingScene {
  WorldGeometry world;
  std::unique_ptr<RaycastScene> scene;
  int id = 0;
  MovingScene(const TriangleMesh& mesh, RaycastScene::PoseFunction X_WO,
              WorldGeometry w = WorldGeometry()) {
    world = std::move(w);
    scene = std::make_unique<RaycastScene>(world);
    id = scene->AddMovingObject(mesh, std::move(X_WO));
  }
};

Eigen::Isometry3d At(const Eigen::Vector3d& p, double yaw_rad = 0.0, double pitch_rad = 0.0) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()))
                   .toRotationMatrix();
  X.translation() = p;
  return X;
}

}  // namespace

TEST_CASE("FmcwRadar: one scatterer's cube is the header's formula, sample by sample",
          "[sensors]") {
  const FmcwRadarConfig c = Quiet({1.0, -2.0, 3.0}, {5.0, -10.0, 30.0});
  const Eigen::Isometry3d X_WR = c.pose.ToIsometry();
  const double az = 20.0 * kPi / 180.0, el = 10.0 * kPi / 180.0, range = 37.3, rcs = 0.5;
  const Eigen::Vector3d u_R(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const Eigen::Vector3d u_W = X_WR.linear() * u_R;
  const Eigen::Vector3d side = u_W.cross(Eigen::Vector3d::UnitZ()).normalized();
  const double v_radial = 4.2;
  const Scatterer s = PointAt(X_WR.translation() + range * u_W, rcs, v_radial * u_W + 3.0 * side);
  const RadarCube cube = SynthesizeOne(c, {s});
  REQUIRE(cube.samples == 512);
  REQUIRE(cube.chirps == 64);
  REQUIRE(cube.nx == 4);
  REQUIRE(cube.ny == 3);

  const double lambda = kC / 77e9, slope = 900e6 / 60e-6, fs = 10e6, tc = 80e-6;
  const double dx = 0.5 * lambda, dy = 0.5 * lambda;
  const double a = std::sqrt(ExpectedSnr(c, rcs, range));
  const double f_b = 2.0 * slope * range / kC;
  double worst = 0.0;
  for (int iy = 0; iy < 3; ++iy)
    for (int ix = 0; ix < 4; ++ix)
      for (int ch = 0; ch < 64; ++ch)
        for (int smp = 0; smp < 512; ++smp) {
          const double phase = 2.0 * kPi * f_b * smp / fs + 4.0 * kPi * range / lambda +
                               2.0 * kPi * (2.0 * v_radial / lambda) * ch * tc +
                               2.0 * kPi * (ix * dx * u_R.y() + iy * dy * u_R.z()) / lambda;
          const std::complex<double> expected = std::polar(a, phase);
          const std::complex<double> got(cube.at(smp, ch, ix, iy));
          worst = std::max(worst, std::abs(got - expected));
        }
  INFO("amplitude " << a << ", worst error " << worst);
  CHECK(worst < 1e-5 * a);
}

TEST_CASE("FmcwRadar: received SNR falls as 40 log10 R and matches the radar equation",
          "[sensors]") {
  FmcwRadarConfig quiet = Quiet();
  FmcwRadarConfig noisy = quiet;
  noisy.thermal_noise = true;
  const double noise_power = MeanPower(SynthesizeOne(noisy, {}));
  const double rcs = 1.0;
  const double snr10_db =
      10.0 * std::log10(MeanPower(SynthesizeOne(quiet, {PointAt({10, 0, 0}, rcs)})) / noise_power);
  for (double r : {10.0, 20.0, 40.0, 80.0}) {
    const double snr_db =
        10.0 * std::log10(MeanPower(SynthesizeOne(quiet, {PointAt({r, 0, 0}, rcs)})) / noise_power);
    INFO("R = " << r << " m, SNR " << snr_db << " dB");
    CHECK(std::abs((snr_db - snr10_db) + 40.0 * std::log10(r / 10.0)) < 1.0);
    CHECK(std::abs(snr_db - 10.0 * std::log10(ExpectedSnr(quiet, rcs, r))) < 0.05);
  }
}

TEST_CASE("FmcwRadar: thermal noise is complex Gaussian of power k T0 fs F per sample",
          "[sensors]") {
  FmcwRadarConfig c = Quiet();
  c.thermal_noise = true;
  WorldGeometry empty;
  RaycastScene scene(empty);
  FmcwRadar radar(c, scene);
  const double k_t_b_f = kBoltzmann * 290.0 * 10e6 * std::pow(10.0, 12.0 / 10.0);
  CHECK(radar.noise_power_w() == Approx(k_t_b_f).epsilon(1e-12));

  RngStream noise(3, "radar1");
  const RadarCube cube = radar.Synthesize({}, WeatherConfig{}, noise);
  const auto n = static_cast<double>(cube.data.size());
  double sum_re = 0, sum_im = 0, sum_re2 = 0, sum_im2 = 0, sum_cross = 0, beyond = 0;
  double adjacent = 0;  // correlation of sample s with the same sample one chirp on
  for (std::size_t i = 0; i < cube.data.size(); ++i) {
    const double re = cube.data[i].real(), im = cube.data[i].imag();
    sum_re += re;
    sum_im += im;
    sum_re2 += re * re;
    sum_im2 += im * im;
    sum_cross += re * im;
    beyond += std::abs(re) > 1.959964 * std::sqrt(0.5);
    if (i + 512 < cube.data.size()) adjacent += re * cube.data[i + 512].real();
  }
  const double power = (sum_re2 + sum_im2) / n;
  // The mean of |n|^2 (Exp(1) per sample) has std 1 / sqrt(n).
  CHECK(std::abs(power - 1.0) < 4.0 / std::sqrt(n));
  CHECK(power * radar.noise_power_w() == Approx(k_t_b_f).epsilon(4.0 / std::sqrt(n)));
  CHECK(std::abs(sum_re2 / n - 0.5) < 4.0 * 0.5 * std::sqrt(2.0 / n));
  CHECK(std::abs(sum_im2 / n - 0.5) < 4.0 * 0.5 * std::sqrt(2.0 / n));
  CHECK(std::abs(sum_re / n) < 4.0 * std::sqrt(0.5 / n));
  CHECK(std::abs(sum_im / n) < 4.0 * std::sqrt(0.5 / n));
  CHECK(std::abs(sum_cross / n) < 4.0 * 0.5 / std::sqrt(n));
  CHECK(std::abs(adjacent / n) < 4.0 * 0.5 / std::sqrt(n));
  const double p = 0.05;  // P(|Z| > 1.96)
  CHECK(std::abs(beyond - n * p) < 4.0 * std::sqrt(n * p * (1 - p)));
}

TEST_CASE("FmcwRadar: backscatter coefficients follow their closed forms", "[sensors]") {
  const FmcwRadarConfig c;
  SECTION("ground clutter at grazing incidence is -20 to -30 dB") {
    for (double grazing_deg : {3.0, 5.0, 8.0}) {
      const double s0 = uavsim::sensors::BackscatterCoefficient(
          c.surfaces.ground, std::sin(grazing_deg * kPi / 180.0));
      INFO("grazing " << grazing_deg << " deg: " << 10 * std::log10(s0) << " dB");
      CHECK(10 * std::log10(s0) < -20.0);
      CHECK(10 * std::log10(s0) > -30.0);
    }
  }
  SECTION("specular faces: gamma + |Gamma0|^2 / (2 m^2) head on, a narrow lobe") {
    for (const RadarSurfaceConfig& s : {c.surfaces.concrete, c.surfaces.glass, c.surfaces.metal}) {
      const double m2 = s.rms_slope * s.rms_slope;
      const double head_on = std::pow(10.0, s.gamma_db / 10.0) + s.fresnel_reflectance / (2 * m2);
      CHECK(uavsim::sensors::BackscatterCoefficient(s, 1.0) == Approx(head_on).epsilon(1e-12));
      const double th = 25.0 * kPi / 180.0, ct = std::cos(th), t2 = std::tan(th) * std::tan(th);
      const double at25 = std::pow(10.0, s.gamma_db / 10.0) * ct + s.fresnel_reflectance *
                                                                       std::exp(-t2 / (2 * m2)) /
                                                                       (2 * m2 * std::pow(ct, 4));
      CHECK(uavsim::sensors::BackscatterCoefficient(s, ct) == Approx(at25).epsilon(1e-12));
      CHECK(head_on > 10.0 * at25);
    }
  }
}

TEST_CASE("FmcwRadar: a wall at known distance gives scatterers on it with its RCS integral",
          "[sensors]") {
  const double d = 20.0, y0 = -6.0, y1 = 6.0, z0 = -4.0, z1 = 4.0;
  WorldGeometry w;
  w.meshes.push_back(
      BoxMesh({static_cast<float>(d), static_cast<float>(y0), static_cast<float>(z0)},
              {static_cast<float>(d + 1), static_cast<float>(y1), static_cast<float>(z1)},
              uavsim::core::kMaterialConcrete));
  RaycastScene scene(w);
  FmcwRadarConfig c = Quiet();
  const std::vector<Scatterer> s = FmcwRadar(c, scene).FindScatterers(0.0);
  // Merged over whole resolution cells: each scatterer sits at its cell's
  // mean range along its mean direction, so behind the plane by at most
  // 1 / cos(the cell's half diagonal, 24 deg at the defaults).
  REQUIRE(s.size() >= 5);
  for (const Scatterer& x : s) {
    CHECK(x.object == 0);
    CHECK(x.velocity_mps.norm() == 0.0);
    CHECK(x.position_m.x() > d - 0.2);
    CHECK(x.position_m.x() < d / std::cos(24.0 * kPi / 180.0));
  }
  SECTION("finely merged: on the plane, within its edges") {
    FmcwRadarConfig f = c;
    f.merge_cell_fraction = 0.02;
    const std::vector<Scatterer> fine = FmcwRadar(f, scene).FindScatterers(0.0);
    REQUIRE(fine.size() > 1000);
    for (const Scatterer& x : fine) {
      CHECK(std::abs(x.position_m.x() - d) < 0.02);
      CHECK(x.position_m.y() > y0 - 0.1);
      CHECK(x.position_m.y() < y1 + 0.1);
      CHECK(x.position_m.z() > z0 - 0.1);
      CHECK(x.position_m.z() < z1 + 0.1);
    }
  }
  // sigma = integral of sigma0(theta) over the face, cos(theta) = d / R
  // (constant-gamma diffuse term plus the geometric-optics lobe).
  const RadarSurfaceConfig& k = c.surfaces.concrete;
  const double gamma = std::pow(10.0, k.gamma_db / 10.0), m2 = k.rms_slope * k.rms_slope;
  double expected = 0.0;
  const double h = 0.005;
  for (double y = y0 + h / 2; y < y1; y += h)
    for (double z = z0 + h / 2; z < z1; z += h) {
      const double r = std::sqrt(d * d + y * y + z * z), ct = d / r;
      const double t2 = (1 - ct * ct) / (ct * ct);
      expected += (gamma * ct + k.fresnel_reflectance * std::exp(-t2 / (2 * m2)) /
                                    (2 * m2 * ct * ct * ct * ct)) *
                  h * h;
    }
  double total = 0.0;
  for (const Scatterer& x : s) total += x.rcs_m2;
  INFO("total " << total << " m^2, expected " << expected);
  CHECK(total == Approx(expected).epsilon(0.03));
}

TEST_CASE("FmcwRadar: a moving box gives scatterers on it with its velocity", "[sensors]") {
  const Eigen::Vector3d p0(30.0, 2.0, 1.0), v(-3.0, 4.0, 1.0);
  MovingScene m(BoxMesh({-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}, uavsim::core::kMaterialMetal),
                [&](double t) { return At(p0 + v * t); });
  const double t = 0.7;
  m.scene->SetTime(t);
  const FmcwRadar radar(Quiet(), *m.scene);
  const std::vector<Scatterer> s = radar.FindScatterers(t);
  REQUIRE(!s.empty());
  const Eigen::Vector3d centre = p0 + v * t;
  for (const Scatterer& x : s) {
    CHECK(x.object == m.id);
    CHECK((x.velocity_mps - v).norm() < 1e-6);
    const Eigen::Vector3d q = x.position_m - centre;
    CHECK(q.cwiseAbs().maxCoeff() < 0.5 + 0.1);
  }
}

TEST_CASE("FmcwRadar: a UAV's total RCS is gamma times its projected area, 0.01-0.1 m^2",
          "[sensors]") {
  const FmcwRadarConfig c = Quiet(Eigen::Vector3d::Zero(), {0.0, -20.0, 0.0});
  const double gamma = std::pow(10.0, c.surfaces.drone.gamma_db / 10.0);
  SECTION("box-shaped drone: projected area |u_x| A_yz + |u_y| A_xz + |u_z| A_xy") {
    const Eigen::Vector3d size(0.5, 0.5, 0.2);
    for (const Eigen::Vector3d& p :
         {Eigen::Vector3d(40, 0, 10), Eigen::Vector3d(30, 15, 20), Eigen::Vector3d(70, -20, 25)}) {
      MovingScene m(BoxMesh((-0.5 * size).cast<float>(), (0.5 * size).cast<float>(),
                            uavsim::core::kMaterialDrone),
                    [&](double) { return At(p); });
      m.scene->SetTime(0.0);
      const FmcwRadar radar(c, *m.scene);
      const Eigen::Vector3d u = p.normalized();
      const double area = std::abs(u.x()) * size.y() * size.z() +
                          std::abs(u.y()) * size.x() * size.z() +
                          std::abs(u.z()) * size.x() * size.y();
      const double total = TotalRcs(radar.FindScatterers(0.0), m.id);
      INFO("at " << p.transpose() << ": " << total << " m^2, expected " << gamma * area);
      CHECK(total == Approx(gamma * area).epsilon(0.05));
    }
  }
  SECTION("default quadrotor from several aspects and ranges") {
    for (double yaw : {0.0, 0.6, 1.2})
      for (const Eigen::Vector3d& p :
           {Eigen::Vector3d(25, 5, 8), Eigen::Vector3d(45, -10, 20), Eigen::Vector3d(80, 20, 28)}) {
        MovingScene m(uavsim::core::MakeQuadrotorMesh({0.5, 0.5, 0.2}),
                      [&](double) { return At(p, yaw, 0.2); });
        m.scene->SetTime(0.0);
        const FmcwRadar radar(c, *m.scene);
        const double total = TotalRcs(radar.FindScatterers(0.0), m.id);
        INFO("yaw " << yaw << " at " << p.transpose() << ": " << total << " m^2");
        CHECK(total > 0.01);
        CHECK(total < 0.1);
      }
  }
  SECTION("refinement makes the total independent of the coarse ray density") {
    const Eigen::Vector3d p(50, 3, 12);
    MovingScene m(uavsim::core::MakeQuadrotorMesh({0.5, 0.5, 0.2}),
                  [&](double) { return At(p, 0.3); });
    m.scene->SetTime(0.0);
    FmcwRadarConfig fine = c, coarse = c;
    coarse.ray_density_deg = 0.4;
    fine.ray_density_deg = 0.1;
    const double a = TotalRcs(FmcwRadar(coarse, *m.scene).FindScatterers(0.0), m.id);
    const double b = TotalRcs(FmcwRadar(fine, *m.scene).FindScatterers(0.0), m.id);
    CHECK(a == Approx(b).epsilon(0.1));
  }
}

TEST_CASE("FmcwRadar: a bounding sphere finds a small UAV between sparse coarse rays",
          "[sensors]") {
  // 1 deg rays are 1.6 m apart at 90 m: a 0.5 m quadrotor usually falls
  // between them. With its bounding sphere passed, its cells are refined
  // anyway and its RCS is that of a dense grid.
  FmcwRadarConfig sparse = Quiet(Eigen::Vector3d::Zero(), {0.0, -10.0, 0.0});
  sparse.ray_density_deg = 1.0;
  sparse.fov_azimuth_deg = 40.0;  // the UAVs below lie within +-15 deg by +-5 deg
  sparse.fov_elevation_deg = 20.0;
  FmcwRadarConfig dense = sparse;
  dense.ray_density_deg = 0.05;
  const Eigen::Vector3d size(0.5, 0.5, 0.2);
  for (int k = 0; k < 6; ++k) {
    const Eigen::Vector3d p(88.0, -20.0 + 7.3 * k, 10.0 + 2.1 * k);
    MovingScene m(uavsim::core::MakeQuadrotorMesh(size), [&](double) { return At(p, 0.5 * k); });
    m.scene->SetTime(0.0);
    const std::vector<uavsim::sensors::BoundingSphere> spheres = {{p, 0.5 * size.norm()}};
    const double with = TotalRcs(FmcwRadar(sparse, *m.scene).FindScatterers(0.0, spheres), m.id);
    const double reference = TotalRcs(FmcwRadar(dense, *m.scene).FindScatterers(0.0), m.id);
    INFO("at " << p.transpose() << ": " << with << " m^2, dense grid " << reference);
    CHECK(with == Approx(reference).epsilon(0.1));
    CHECK(with > 0.01);
    CHECK(with < 0.1);
  }
}

TEST_CASE("FmcwRadar: rain at 25 mm/h attenuates by 2 gamma R with P.838-3's gamma at 77 GHz",
          "[sensors]") {
  FmcwRadarConfig c = Quiet();
  c.rain_clutter = false;
  const double r = 50.0;
  const std::vector<Scatterer> s = {PointAt({r, 0, 0}, 1.0)};
  WeatherConfig wet;
  wet.rain_mm_h = 25.0;
  const double loss_db =
      10.0 * std::log10(MeanPower(SynthesizeOne(c, s)) / MeanPower(SynthesizeOne(c, s, wet)));
  const double gamma_db_per_km = uavsim::core::RainSpecificAttenuationDbPerKm(
      77.0, 25.0, uavsim::core::Polarization::kHorizontal);
  INFO("gamma " << gamma_db_per_km << " dB/km, loss " << loss_db << " dB");
  CHECK(loss_db == Approx(2.0 * gamma_db_per_km * r / 1000.0).epsilon(1e-3));
}

TEST_CASE("FmcwRadar: at 77 GHz its P.838-3 coefficients are the former k = 1.1320, alpha = 0.7177",
          "[sensors]") {
  // The defaults the config hard-coded (horizontal polarisation, 77 GHz),
  // given to four decimals.
  WorldGeometry empty;
  RaycastScene scene(empty);
  const FmcwRadar radar(Quiet(), scene);
  CHECK(radar.rain_coefficients().k == Approx(1.1320).margin(5e-5));
  CHECK(radar.rain_coefficients().alpha == Approx(0.7177).margin(5e-5));
  CHECK(radar.RainAttenuationDbPerKm(25.0) ==
        Approx(1.1320 * std::pow(25.0, 0.7177)).epsilon(1e-4));
  CHECK(radar.RainAttenuationDbPerKm(0.0) == 0.0);
}

TEST_CASE("FmcwRadar: at 24 GHz its rain attenuation equals the uplink's at 24 GHz", "[sensors]") {
  using uavsim::core::Polarization;
  const double rain_mm_h = 10.0;
  for (const Polarization pol :
       {Polarization::kHorizontal, Polarization::kVertical, Polarization::kCircular}) {
    FmcwRadarConfig c = Quiet();
    c.carrier_ghz = 24.0;
    c.polarization = pol;
    WorldGeometry empty;
    RaycastScene scene(empty);
    const FmcwRadar radar(c, scene);

    uavsim::channel::LinkConfig l;
    l.carrier_ghz = 24.0;
    l.polarization = pol;
    l.path_length_m = 1000.0;  // so the link's loss in dB is gamma in dB/km
    l.path_elevation_deg = 0.0;
    uavsim::core::Simulator sim;
    const uavsim::channel::Uplink link(sim, l, WeatherConfig{rain_mm_h, {}, 1.0},
                                       RngStream(1, "link/test"), {});
    INFO("polarisation " << static_cast<int>(pol));
    REQUIRE(link.rain_attenuation_db() > 0.0);
    CHECK(radar.RainAttenuationDbPerKm(rain_mm_h) == Approx(link.rain_attenuation_db()));
  }
}

// Expected rain-clutter power per sample: eta times the integral over the
// field of view and range (r_min to the last range bin's far edge, or the
// first surface along each direction) of R^2 dR dOmega times the SNR of
// 1 m^2 at R with the two-way rain loss. `free_range` gives the distance to
// the first surface along a radar-frame direction.
double ExpectedRainPower(const FmcwRadarConfig& c, double rain_mm_h, double eta, double r_min,
                         const std::function<double(const Eigen::Vector3d&)>& free_range) {
  const double gamma_db_per_km = uavsim::core::RainSpecificAttenuationDbPerKm(
      77.0, rain_mm_h, uavsim::core::Polarization::kHorizontal);
  const double r_bin = 10e6 * kC / (2.0 * 900e6 / 60e-6) / 512.0;
  const double r_end = 511.5 * r_bin;
  // R^2 times the SNR of 1 m^2 at R is k0 / R^2 (k0 = SNR at 1 m) times the
  // rain loss: its running integral from r_min, tabulated once.
  const double k0 = ExpectedSnr(c, 1.0, 1.0), h = 1e-3;
  std::vector<double> running = {0.0};
  for (double r = r_min + h / 2; r < r_end; r += h)
    running.push_back(running.back() +
                      k0 / (r * r) * std::pow(10.0, -2.0 * gamma_db_per_km * r / 1e4) * h);
  auto along = [&](double r_stop) {
    const double x = std::clamp((r_stop - r_min) / h, 0.0, static_cast<double>(running.size() - 1));
    const auto i = static_cast<std::size_t>(x);
    if (i + 1 >= running.size()) return running.back();
    return running[i] + (x - i) * (running[i + 1] - running[i]);
  };
  double total = 0.0;
  const double step = 0.25 * kPi / 180.0;
  for (double el = -30 * kPi / 180 + step / 2; el < 30 * kPi / 180; el += step)
    for (double az = -60 * kPi / 180 + step / 2; az < 60 * kPi / 180; az += step) {
      const Eigen::Vector3d u(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                              std::sin(el));
      total += eta * along(std::min(r_end, free_range(u))) * std::cos(el) * step * step;
    }
  return total;
}

TEST_CASE("FmcwRadar: rain clutter power follows its eta law over the visible field of view",
          "[sensors]") {
  const FmcwRadarConfig c = Quiet();
  WeatherConfig wet;
  wet.rain_mm_h = 25.0;
  const double eta = 4.07e-4 * std::pow(25.0, 0.79);
  RngStream noise(11, "radar1");
  SECTION("open sky: all the way out") {
    WorldGeometry empty;
    RaycastScene scene(empty);
    const FmcwRadar radar(c, scene);
    CHECK(radar.RainReflectivityPerM(25.0) == Approx(eta).epsilon(1e-12));
    const double expected =
        ExpectedRainPower(c, 25.0, eta, 1.0, [](const Eigen::Vector3d&) { return 1e9; });
    double measured = 0.0;
    for (int f = 0; f < 4; ++f) measured += MeanPower(radar.Synthesize({}, wet, noise)) / 4;
    INFO("measured " << measured << ", expected " << expected);
    CHECK(measured == Approx(expected).epsilon(0.1));
    CHECK(MeanPower(radar.Synthesize({}, WeatherConfig{}, noise)) == 0.0);  // dry: nothing
  }
  SECTION("a wall at 10 m hides the rain behind it") {
    FmcwRadarConfig from5 = c;
    from5.rain_clutter_min_range_m = 5.0;
    WorldGeometry w;
    w.meshes.push_back(BoxMesh({10, -100, -100}, {11, 100, 100}, uavsim::core::kMaterialConcrete));
    RaycastScene scene(w);
    const FmcwRadar radar(from5, scene);
    const double expected = ExpectedRainPower(
        from5, 25.0, eta, 5.0, [](const Eigen::Vector3d& u) { return 10.0 / u.x(); });
    const double open =
        ExpectedRainPower(from5, 25.0, eta, 5.0, [](const Eigen::Vector3d&) { return 1e9; });
    REQUIRE(expected < 0.7 * open);
    double measured = 0.0;
    for (int f = 0; f < 4; ++f) measured += MeanPower(radar.Synthesize({}, wet, noise)) / 4;
    INFO("measured " << measured << ", expected " << expected << ", without the wall " << open);
    CHECK(measured == Approx(expected).epsilon(0.1));
  }
}

TEST_CASE("FmcwRadar: rain seen upward approaches at the mean fall speed times sin(el)",
          "[sensors]") {
  // Pulse-pair estimate of the mean radial velocity: the phase of the lag-1
  // correlation over chirps is 4 pi v T_c / lambda.
  const FmcwRadarConfig c = Quiet(Eigen::Vector3d::Zero(), {0.0, -30.0, 0.0});
  WorldGeometry empty;
  RaycastScene scene(empty);
  const FmcwRadar radar(c, scene);
  WeatherConfig wet;
  wet.rain_mm_h = 25.0;
  RngStream noise(5, "radar1");
  std::complex<double> lag1 = 0.0;
  for (int f = 0; f < 2; ++f) {
    const RadarCube cube = radar.Synthesize({}, wet, noise);
    for (int a = 0; a < 12; ++a)
      for (int ch = 0; ch + 1 < 64; ++ch)
        for (int smp = 0; smp < 512; ++smp)
          lag1 += std::complex<double>(cube.at(smp, ch + 1, a % 4, a / 4)) *
                  std::conj(std::complex<double>(cube.at(smp, ch, a % 4, a / 4)));
  }
  const double lambda = kC / 77e9, tc = 80e-6;
  const double v_mean = std::arg(lag1) * lambda / (4.0 * kPi * tc);
  // Independently: fall speed (Atlas et al. 1973) averaged over D^6 N(D)
  // (Marshall-Palmer), times the mean upward direction cosine over the
  // field of view, weighted by solid angle (world elevations 0 to 60 deg).
  const double lam = 4.1 * std::pow(25.0, -0.21);
  double num = 0.0, den = 0.0;
  for (double d = 0.005; d < 15.0; d += 0.01) {
    const double w = std::pow(d, 6) * std::exp(-lam * d);
    num += w * std::max(0.0, 9.65 - 10.3 * std::exp(-0.6 * d));
    den += w;
  }
  const double fall = num / den;
  double up = 0.0, sr = 0.0;
  for (double el = 0.0005; el < kPi / 3; el += 0.001) {
    up += std::sin(el) * std::cos(el);
    sr += std::cos(el);
  }
  const double expected = -fall * up / sr;
  INFO("pulse-pair " << v_mean << " m/s, expected " << expected << " m/s");
  CHECK(v_mean < 0.0);
  CHECK(v_mean == Approx(expected).epsilon(0.15));
}

TEST_CASE("FmcwRadar: ground multipath adds the image paths of a moving scatterer", "[sensors]") {
  WorldGeometry ground;
  ground.meshes.push_back(BoxMesh({-200, -200, -1}, {200, 200, 0}, uavsim::core::kMaterialGround));
  const Eigen::Vector3d p(20.0, 0.0, 3.0);
  MovingScene m(
      BoxMesh({-0.1f, -0.1f, -0.1f}, {0.1f, 0.1f, 0.1f}, uavsim::core::kMaterialDrone),
      [&](double) { return At(p); }, ground);
  m.scene->SetTime(0.0);
  FmcwRadarConfig c = Quiet({0.0, 0.0, 1.5});
  {
    const std::vector<Scatterer> off = FmcwRadar(c, *m.scene).FindScatterers(0.0);
    CHECK(std::none_of(off.begin(), off.end(), [](const Scatterer& s) { return s.multipath; }));
  }
  c.multipath = true;
  c.multipath_reflection = 0.4;
  const FmcwRadar radar(c, *m.scene);
  const std::vector<Scatterer> s = radar.FindScatterers(0.0);
  std::vector<Scatterer> direct, paths;
  for (const Scatterer& x : s)
    if (x.object == m.id) (x.multipath ? paths : direct).push_back(x);
  REQUIRE(!direct.empty());
  REQUIRE(paths.size() == 3 * direct.size());
  const Eigen::Vector3d o(0.0, 0.0, 1.5);
  const double rho = 0.4;
  for (std::size_t k = 0; k < direct.size(); ++k) {
    const Eigen::Vector3d q = direct[k].position_m;
    const Eigen::Vector3d img(q.x(), q.y(), -q.z());
    const double r = (q - o).norm(), ri = (img - o).norm(), rm = 0.5 * (r + ri);
    const double mixed = direct[k].rcs_m2 * rho * rho * std::pow(rm, 4) / (r * r * ri * ri);
    // Out direct and back via the ground: arrives from the image direction.
    CHECK(((paths[3 * k].position_m - o) - rm * (img - o).normalized()).norm() < 1e-9);
    CHECK(paths[3 * k].rcs_m2 == Approx(mixed).epsilon(1e-9));
    // The reverse: arrives from the direct direction.
    CHECK(((paths[3 * k + 1].position_m - o) - rm * (q - o).normalized()).norm() < 1e-9);
    CHECK(paths[3 * k + 1].rcs_m2 == Approx(mixed).epsilon(1e-9));
    // Via the ground both ways: the image, rho^4.
    CHECK((paths[3 * k + 2].position_m - img).norm() < 1e-9);
    CHECK(paths[3 * k + 2].rcs_m2 == Approx(direct[k].rcs_m2 * std::pow(rho, 4)).epsilon(1e-9));
  }
}

TEST_CASE("FmcwRadar: same seed, same cube, one or two threads, same cube", "[sensors]") {
  WorldGeometry w;
  w.meshes.push_back(BoxMesh({25, -10, -3}, {26, 10, 8}, uavsim::core::kMaterialGlass));
  w.meshes.push_back(BoxMesh({-100, -100, -2}, {100, 100, -1.5f}, uavsim::core::kMaterialGround));
  const Eigen::Vector3d p0(18.0, -3.0, 2.0), v(2.0, 3.0, 0.5);
  MovingScene m(
      uavsim::core::MakeQuadrotorMesh({0.5, 0.5, 0.2}),
      [&](double t) { return At(p0 + v * t, 0.4); }, w);
  FmcwRadarConfig c = Quiet({0.0, 0.0, 0.0}, {0.0, -5.0, 0.0});
  c.thermal_noise = true;
  c.multipath = true;
  WeatherConfig rain;
  rain.rain_mm_h = 5.0;
  m.scene->SetTime(0.1);
  const FmcwRadar radar(c, *m.scene);

  auto run = [&](int threads, std::uint64_t seed) {
    tbb::task_arena arena(threads);
    std::pair<std::vector<Scatterer>, RadarCube> out;
    arena.execute([&] {
      RngStream noise(seed, "radar1");
      out.first = radar.FindScatterers(0.1);
      out.second = radar.Synthesize(out.first, rain, noise);
    });
    return out;
  };
  auto same_cube = [](const RadarCube& a, const RadarCube& b) {
    return a.data.size() == b.data.size() &&
           std::memcmp(a.data.data(), b.data.data(), a.RawBytes()) == 0;
  };
  auto same_scatterers = [](const std::vector<Scatterer>& a, const std::vector<Scatterer>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t k = 0; k < a.size(); ++k)
      if (a[k].position_m != b[k].position_m || a[k].velocity_mps != b[k].velocity_mps ||
          a[k].rcs_m2 != b[k].rcs_m2 || a[k].object != b[k].object)
        return false;
    return true;
  };
  const auto one = run(1, 42), two = run(2, 42), again = run(2, 42), other = run(2, 43);
  REQUIRE(std::any_of(one.first.begin(), one.first.end(),
                      [&](const Scatterer& s) { return s.object == m.id; }));
  CHECK(same_scatterers(one.first, two.first));
  CHECK(same_cube(one.second, two.second));
  CHECK(same_cube(two.second, again.second));
  CHECK_FALSE(same_cube(two.second, other.second));
}

TEST_CASE("FmcwRadarConfig: new keys have defaults, rules and clear errors", "[sensors]") {
  using uavsim::core::ConfigError;
  using uavsim::core::Json;
  const Json defaults = uavsim::core::ToJson(FmcwRadarConfig{});
  CHECK(defaults["polarization"] == "horizontal");
  CHECK_FALSE(defaults.contains("rain_attenuation_k"));
  CHECK(defaults["surfaces"]["drone"]["gamma_db"] == -5.0);
  CHECK(defaults["multipath"] == false);
  CHECK(defaults.contains("processing"));

  auto read = [](const std::string& text) {
    FmcwRadarConfig c;
    uavsim::core::FromJson(uavsim::core::ParseJsonText(text, "radar.json"), "radar.json", "", c);
    return c;
  };
  CHECK(read(R"({"surfaces": {"glass": {"rms_slope": 0.05}}})").surfaces.glass.rms_slope == 0.05);
  CHECK_THROWS_WITH(read(R"({"object_ray_spacing_m": 0})"),
                    Catch::Contains("/object_ray_spacing_m") && Catch::Contains("[0.001, 10]"));
  CHECK_THROWS_WITH(read(R"({"surfaces": {"concret": {}}})"),
                    Catch::Contains("/surfaces/concret") && Catch::Contains("concrete"));
  CHECK_THROWS_WITH(read(R"({"multipath_reflection": 1.5})"),
                    Catch::Contains("/multipath_reflection"));

  WorldGeometry empty;
  RaycastScene scene(empty);
  FmcwRadarConfig bad;
  bad.merge_cell_fraction = 0.0;
  CHECK_THROWS_AS(FmcwRadar(bad, scene), std::invalid_argument);
  CHECK_THROWS_WITH(FmcwRadar(bad, scene), Catch::Contains("merge_cell_fraction"));
}
