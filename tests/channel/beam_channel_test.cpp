// The downlink channel against closed forms: Friis, rain, the image method's
// mirror geometry, blockage, and the normalisation gamma = Mx My |alpha|^2.
#include "channel/beam_channel.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <complex>
#include <functional>
#include <string>

#include "channel/beamformer.h"
#include "core/error.h"
#include "core/json_io.h"

using uavsim::channel::BaseStationConfig;
using uavsim::channel::BeamChannel;
using uavsim::channel::DownlinkChannel;
using uavsim::channel::FreeSpace;
using uavsim::channel::PathKind;
using uavsim::channel::PathModel;
using uavsim::channel::PathOracle;
using uavsim::channel::SnrReference;
using uavsim::core::Facade;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kC = 299792458.0;

// Closed-form world: a list of facades and a blocking rule.
class TestWorld : public PathOracle {
 public:
  std::vector<Facade> facades;
  std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)> blocked =
      [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return false; };

  bool Blocked(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const override {
    return blocked(a, b);
  }
  const std::vector<Facade>& Reflectors() const override { return facades; }
};

// The plane x = 20 facing -x (towards the base station at the origin).
Facade WallAtX20(double half_size_m) {
  Facade f;
  f.center_m = {20.0, 0.0, 50.0};
  f.normal = {-1.0, 0.0, 0.0};
  f.u_axis = {0.0, 1.0, 0.0};
  f.half_width_m = half_size_m;
  f.half_height_m = half_size_m;
  f.material = uavsim::core::kMaterialConcrete;
  return f;
}

BaseStationConfig Station() {
  BaseStationConfig c;
  c.position_m = {0.0, 0.0, 10.0};
  return c;
}

std::string ConfigErrorOf(const uavsim::core::Json& j) {
  BaseStationConfig c;
  try {
    uavsim::core::FromJson(j, "bs.json", "/base_station", c);
  } catch (const uavsim::core::ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("BeamChannel: free-space loss is (4 pi d / lambda)^2 at 28 GHz", "[channel]") {
  const BaseStationConfig bs = Station();
  const BeamChannel channel(bs);
  const double lambda_m = kC / 28e9;
  CHECK(channel.wavelength_m() == Approx(lambda_m).epsilon(1e-15));
  const Eigen::Vector3d uav = bs.position_m + Eigen::Vector3d(60.0, 0.0, 80.0);  // 100 m
  const DownlinkChannel h = channel.Realize(uav, FreeSpace());
  REQUIRE(h.paths.size() == 1);
  const double fspl = std::pow(4.0 * kPi * 100.0 / lambda_m, 2.0);
  CHECK(std::norm(h.paths[0].alpha) == Approx(1.0 / fspl).epsilon(1e-12));
  CHECK(10.0 * std::log10(fspl) == Approx(101.39).margin(0.01));  // the textbook figure
  // Carrier phase exp(-j 2 pi d / lambda).
  const std::complex<double> expected =
      std::polar(std::sqrt(1.0 / fspl), -2.0 * kPi * 100.0 / lambda_m);
  CHECK(std::abs(h.paths[0].alpha - expected) < 1e-9 * std::abs(expected));
}

TEST_CASE("BeamChannel: LOS only, perfect beam: gamma = Mx My |alpha|^2 and the rate formula",
          "[channel]") {
  for (const auto& [mx, my] : {std::pair{8, 8}, std::pair{4, 16}, std::pair{1, 1}}) {
    BaseStationConfig bs = Station();
    bs.upa.mx = mx;
    bs.upa.my = my;
    const BeamChannel channel(bs);
    const Eigen::Vector3d uav(17.0, -9.0, 42.0);
    const DownlinkChannel h = channel.Realize(uav, FreeSpace());
    REQUIRE(h.paths.size() == 1);
    // Default normalisation: the LOS free-space gain at the true distance, so |alpha| = 1.
    const double alpha2 = std::norm(h.paths[0].alpha) / h.reference_gain;
    CHECK(alpha2 == Approx(1.0).epsilon(1e-12));
    const Eigen::VectorXcd f = uavsim::channel::SteeredBeam(channel.upa(), bs.position_m, uav);
    CHECK(f.norm() == Approx(1.0).epsilon(1e-14));
    const double gamma = uavsim::channel::BeamGain(h.h, f);
    CHECK(gamma == Approx(mx * my * alpha2).epsilon(1e-9));
    for (const double snr_db : {-10.0, 0.0, 13.0, 30.0})
      CHECK(uavsim::channel::RateBpsHz(snr_db, gamma) ==
            std::log2(1.0 + std::pow(10.0, snr_db / 10.0) * gamma));
  }
}

TEST_CASE("BeamChannel: reference distance and rain scale gamma by closed forms", "[channel]") {
  BaseStationConfig bs = Station();
  bs.snr_reference = SnrReference::kReferenceDistance;
  bs.reference_distance_m = 50.0;
  const Eigen::Vector3d uav = bs.position_m + Eigen::Vector3d(0.0, 0.0, 1000.0);
  const BeamChannel dry(bs);
  const DownlinkChannel h = dry.Realize(uav, FreeSpace());
  const Eigen::VectorXcd f = uavsim::channel::SteeredBeam(dry.upa(), bs.position_m, uav);
  CHECK(uavsim::channel::BeamGain(h.h, f) ==
        Approx(64.0 * std::pow(50.0 / 1000.0, 2)).epsilon(1e-9));
  // ITU-R P.838 gives about 4.6 dB/km at 28 GHz and 25 mm/h: 1 km of it.
  const BeamChannel wet(bs, 4.6);
  const DownlinkChannel hw = wet.Realize(uav, FreeSpace());
  CHECK(uavsim::channel::BeamGain(hw.h, f) ==
        Approx(64.0 * std::pow(50.0 / 1000.0, 2) * std::pow(10.0, -0.46)).epsilon(1e-9));
  CHECK_THROWS_AS(BeamChannel(bs, -1.0), std::invalid_argument);
}

TEST_CASE("BeamChannel: image method mirrors the UAV in the facade plane", "[channel]") {
  const BaseStationConfig bs = Station();
  const BeamChannel channel(bs);
  TestWorld world;
  world.facades = {WallAtX20(1000.0)};
  const Eigen::Vector3d uav(10.0, 5.0, 30.0);
  const DownlinkChannel h = channel.Realize(uav, world);
  REQUIRE(h.paths.size() == 2);
  CHECK(h.paths[0].kind == PathKind::kLineOfSight);
  const auto& r = h.paths[1];
  REQUIRE(r.kind == PathKind::kReflection);
  CHECK(r.facade == 0);

  // Mirror image of the UAV in x = 20: (30, 5, 30).
  const Eigen::Vector3d image(30.0, 5.0, 30.0);
  CHECK(r.length_m == Approx((image - bs.position_m).norm()).epsilon(1e-14));
  // Where the straight line to the image crosses x = 20 (t = 20 / 30).
  const Eigen::Vector3d bounce = bs.position_m + (20.0 / 30.0) * (image - bs.position_m);
  CHECK((r.bounce_m - bounce).norm() < 1e-12);
  CHECK((r.departure_W - (bounce - bs.position_m).normalized()).norm() < 1e-14);
  CHECK(r.length_m ==
        Approx((bounce - bs.position_m).norm() + (uav - bounce).norm()).epsilon(1e-14));
  // The departure angles name the same direction in the array frame.
  CHECK((channel.upa().R_WA() * uavsim::channel::Upa::Direction(r.angles) - r.departure_W).norm() <
        1e-12);
  // Amplitude: -10^(-6 dB / 20) (concrete) x Friis x carrier phase.
  const double lambda_m = kC / 28e9;
  const std::complex<double> expected = -std::pow(10.0, -6.0 / 20.0) * lambda_m /
                                        (4.0 * kPi * r.length_m) *
                                        std::polar(1.0, -2.0 * kPi * r.length_m / lambda_m);
  CHECK(std::abs(r.alpha - expected) < 1e-9 * std::abs(expected));
}

TEST_CASE("BeamChannel: a reflection needs its point on the facade and both sides in front",
          "[channel]") {
  const BaseStationConfig bs = Station();
  const BeamChannel channel(bs);
  TestWorld world;
  world.facades = {WallAtX20(1.0)};  // bounce at (20, 3.3, 23.3) is outside this small facade
  CHECK(channel.Realize({10.0, 5.0, 30.0}, world).paths.size() == 1);
  world.facades = {WallAtX20(1000.0)};
  CHECK(channel.Realize({25.0, 5.0, 30.0}, world).paths.size() == 1);  // UAV behind the wall
}

TEST_CASE("BeamChannel: a blocked LOS removes the LOS term", "[channel]") {
  const BaseStationConfig bs = Station();
  const BeamChannel channel(bs);
  const Eigen::Vector3d uav(10.0, 5.0, 30.0);
  TestWorld world;
  world.blocked = [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return true; };
  const DownlinkChannel none = channel.Realize(uav, world);
  CHECK(none.los_blocked);
  CHECK(none.paths.empty());
  CHECK(none.h.norm() == 0.0);
  CHECK(uavsim::channel::BeamGain(
            none.h, uavsim::channel::SteeredBeam(channel.upa(), bs.position_m, uav)) == 0.0);

  // Only the direct segment blocked: the reflection alone remains, and a beam
  // steered along it gets Mx My |alpha_r|^2 / g_ref.
  world.facades = {WallAtX20(1000.0)};
  world.blocked = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return (a - bs.position_m).norm() < 1e-9 && (b - uav).norm() < 1e-9;
  };
  const DownlinkChannel h = channel.Realize(uav, world);
  CHECK(h.los_blocked);
  REQUIRE(h.paths.size() == 1);
  REQUIRE(h.paths[0].kind == PathKind::kReflection);
  const Eigen::Vector3d image(30.0, 5.0, 30.0);
  const Eigen::VectorXcd f = uavsim::channel::SteeredBeam(channel.upa(), bs.position_m, image);
  CHECK(uavsim::channel::BeamGain(h.h, f) ==
        Approx(64.0 * std::norm(h.paths[0].alpha) / h.reference_gain).epsilon(1e-9));
  // A blocked leg removes the reflection too.
  world.blocked = [&](const Eigen::Vector3d&, const Eigen::Vector3d& b) {
    return (b - uav).norm() < 1e-9;
  };
  CHECK(channel.Realize(uav, world).paths.empty());
}

TEST_CASE("BeamChannel: paths behind the panel are dropped", "[channel]") {
  BaseStationConfig bs = Station();
  bs.boresight_el_deg = 0.0;  // facing +x
  const BeamChannel channel(bs);
  CHECK(channel.Realize({50.0, 3.0, 12.0}, FreeSpace()).paths.size() == 1);
  CHECK(channel.Realize({-50.0, 3.0, 12.0}, FreeSpace()).paths.empty());
}

TEST_CASE("BeamChannel: clusters carry 1/K of the LOS power and follow their stream", "[channel]") {
  BaseStationConfig bs = Station();
  bs.path_model = PathModel::kClusters;
  bs.clusters.count = 4;
  bs.clusters.k_factor_db = 10.0;
  const BeamChannel channel(bs);
  const Eigen::Vector3d uav(5.0, 5.0, 60.0);
  uavsim::core::RngStream a(7, "downlink"), b(7, "downlink"), c(8, "downlink");
  const DownlinkChannel ha = channel.Realize(uav, FreeSpace(), &a);
  const DownlinkChannel hb = channel.Realize(uav, FreeSpace(), &b);
  const DownlinkChannel hc = channel.Realize(uav, FreeSpace(), &c);
  REQUIRE(ha.paths.size() == 5);
  double nlos = 0.0;
  for (std::size_t i = 1; i < ha.paths.size(); ++i) nlos += std::norm(ha.paths[i].alpha);
  CHECK(nlos == Approx(std::norm(ha.paths[0].alpha) / 10.0).epsilon(1e-12));
  CHECK((ha.h - hb.h).norm() == 0.0);
  CHECK((ha.h - hc.h).norm() > 0.0);
  CHECK_THROWS_AS(channel.Realize(uav, FreeSpace()), std::invalid_argument);
}

TEST_CASE("BaseStationConfig: defaults, round trip and messages", "[channel]") {
  using uavsim::core::Json;
  CHECK(ConfigErrorOf(Json::object()).empty());
  const BaseStationConfig d;
  CHECK(d.upa.mx == 8);
  CHECK(d.carrier_ghz == 28.0);
  CHECK(d.path_model == PathModel::kImage);
  const Json written = uavsim::core::ToJson(d);
  CHECK(written["path_model"] == "image");
  CHECK(written["beams"] == Json::array({"steered"}));
  CHECK_FALSE(written.contains("clusters"));  // keys of another path model are not written
  CHECK(ConfigErrorOf(written).empty());

  CHECK(ConfigErrorOf(Json{{"boresight_el_deg", 95}}) ==
        "bs.json: /base_station/boresight_el_deg: expected a number in [-90, 90], got 95");
  CHECK_THAT(ConfigErrorOf(Json{{"clusters", {{"count", 2}}}}),
             Catch::StartsWith("bs.json: /base_station/clusters: unknown key"));
  CHECK(ConfigErrorOf(Json{{"path_model", "clusters"}, {"clusters", {{"count", 2}}}}).empty());
  CHECK_THAT(
      ConfigErrorOf(Json{{"beams", {"dft", "laser"}}}),
      Catch::StartsWith("bs.json: /base_station/beams/1: expected one of \"steered\", \"dft\""));
  CHECK_THAT(ConfigErrorOf(Json{{"beams", Json::array()}}), Catch::Contains("at least one"));
  CHECK(ConfigErrorOf(Json{{"beams", {"dft"}}, {"dft_oversampling", 4}}).empty());
  CHECK_THAT(ConfigErrorOf(Json{{"dft_oversampling", 4}}),
             Catch::StartsWith("bs.json: /base_station/dft_oversampling: unknown key"));
  CHECK_THAT(ConfigErrorOf(Json{{"path_model", "rays"}}),
             Catch::Contains("expected one of \"los_only\", \"image\", \"clusters\""));
}
