// The optical atmosphere (sensors/atmosphere.h) against closed forms written
// out here from the cited laws: Koschmieder's 3.912 / V at 550 nm, Kim et
// al.'s q(V) at 905 nm, Marshall-Palmer rain pi N0 / Lambda^3; and the
// camera and the LiDAR attenuating by the same atmosphere (issue 42 item 5),
// down to the radiance the camera renders through rain.
#include "sensors/atmosphere.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstddef>
#include <vector>

#include "core/weather.h"
#include "core/world_geometry.h"
#include "sensors/fisheye_stereo.h"
#include "sensors/lidar_atmosphere.h"
#include "sensors/raycast_scene.h"

namespace uavsim::sensors {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Kim et al. 2001: alpha = 3.912 / V (lambda / 550 nm)^-q.
double KimFog(double visibility_m, double wavelength_nm, double q) {
  return 3.912 / visibility_m * std::pow(wavelength_nm / 550.0, -q);
}

// Marshall-Palmer drops with Q_ext = 2: alpha = 2 (pi / 4) N0 integral D^2
// e^(-Lambda D) dD = pi N0 / Lambda^3, Lambda = 4.1 R^-0.21 /mm, N0 = 8000
// m^-3 mm^-1; mm^2 per m^3 is 1e-6 /m.
double MarshallPalmerRain(double rain_mm_h) {
  const double lambda_per_mm = 4.1 * std::pow(rain_mm_h, -0.21);
  return kPi * 8000.0 / std::pow(lambda_per_mm, 3) * 1e-6;
}

core::WeatherConfig Weather(double rain_mm_h, double visibility_m = 0.0) {
  core::WeatherConfig w;
  w.rain_mm_h = rain_mm_h;
  if (visibility_m > 0.0) w.fog_visibility_m = visibility_m;
  return w;
}

}  // namespace

TEST_CASE("Atmosphere: fog at 550 nm is Koschmieder's 3.912 / V", "[sensors]") {
  CHECK(kVisibleWavelengthNm == 550.0);
  CHECK(kKoschmieder == Approx(-std::log(0.02)).epsilon(1e-4));  // 2 % contrast
  for (double visibility_m : {300.0, 1000.0, 5000.0}) {
    INFO("visibility " << visibility_m << " m");
    // q(V) applies relative to 550 nm, so it drops out there: exactly 3.912 / V.
    CHECK(FogExtinctionPerM(visibility_m, kVisibleWavelengthNm) == 3.912 / visibility_m);
    CHECK(OpticalExtinctionPerM(Weather(0.0, visibility_m), kVisibleWavelengthNm) ==
          3.912 / visibility_m);
  }
}

TEST_CASE("Atmosphere: fog at 905 nm follows Kim et al.'s q(V)", "[sensors]") {
  CHECK(kLidarWavelengthNm == 905.0);
  struct Case {
    double visibility_m, q;
  };
  // q = 0 up to 0.5 km, V - 0.5 up to 1 km, 0.16 V + 0.34 up to 6 km, 1.3 up
  // to 50 km, 1.6 beyond (V in km).
  for (const Case& k : {Case{300.0, 0.0}, Case{800.0, 0.3}, Case{1000.0, 0.5},
                        Case{3000.0, 0.16 * 3 + 0.34}, Case{10000.0, 1.3}, Case{60000.0, 1.6}}) {
    INFO("visibility " << k.visibility_m << " m");
    const double alpha = FogExtinctionPerM(k.visibility_m, kLidarWavelengthNm);
    CHECK(alpha == Approx(KimFog(k.visibility_m, 905.0, k.q)).epsilon(1e-12));
    // The exponent itself, read back from the ratio to Koschmieder's value.
    CHECK(-std::log(alpha * k.visibility_m / 3.912) / std::log(905.0 / 550.0) ==
          Approx(k.q).margin(1e-9));
  }
  // Dense fog scatters every wavelength alike; thinner fog less in the infrared.
  CHECK(FogExtinctionPerM(300.0, kLidarWavelengthNm) == Approx(3.912 / 300.0).epsilon(1e-12));
  CHECK(FogExtinctionPerM(3000.0, kLidarWavelengthNm) < 3.912 / 3000.0);
}

TEST_CASE("Atmosphere: rain is Marshall-Palmer pi N0 / Lambda^3 at every wavelength", "[sensors]") {
  for (double rain_mm_h : {10.0, 25.0}) {
    INFO("rain " << rain_mm_h << " mm/h");
    const double alpha = MarshallPalmerRain(rain_mm_h);
    CHECK(RainExtinctionPerM(rain_mm_h) == Approx(alpha).epsilon(1e-12));
    CHECK(OpticalExtinctionPerM(Weather(rain_mm_h), kVisibleWavelengthNm) ==
          Approx(alpha).epsilon(1e-12));
    CHECK(OpticalExtinctionPerM(Weather(rain_mm_h), kLidarWavelengthNm) ==
          Approx(alpha).epsilon(1e-12));
    // The power law it reduces to: 3.65e-4 R^0.63 /m.
    CHECK(alpha == Approx(3.6466e-4 * std::pow(rain_mm_h, 0.63)).epsilon(1e-4));
  }
  CHECK(MarshallPalmerRain(25.0) == Approx(2.77e-3).epsilon(2e-3));
  CHECK(RainExtinctionPerM(0.0) == 0.0);
  CHECK(OpticalExtinctionPerM(Weather(0.0), kVisibleWavelengthNm) == 0.0);
  // Fog and rain add.
  CHECK(OpticalExtinctionPerM(Weather(10.0, 3000.0), kLidarWavelengthNm) ==
        Approx(MarshallPalmerRain(10.0) + KimFog(3000.0, 905.0, 0.82)).epsilon(1e-12));
}

TEST_CASE("Atmosphere: the camera's and the LiDAR's extinction agree", "[sensors]") {
  for (const core::WeatherConfig& w :
       {Weather(0.0), Weather(10.0), Weather(25.0), Weather(0.0, 300.0), Weather(0.0, 1000.0),
        Weather(0.0, 5000.0), Weather(10.0, 300.0), Weather(25.0, 3000.0)}) {
    INFO("rain " << w.rain_mm_h << " mm/h, fog " << w.fog_visibility_m.value_or(0.0) << " m");
    // Each sensor is the shared atmosphere at its own wavelength.
    CHECK(CameraExtinctionPerM(w) == OpticalExtinctionPerM(w, kVisibleWavelengthNm));
    CHECK(AtmosphericExtinctionPerM(w) == OpticalExtinctionPerM(w, kLidarWavelengthNm));
    // The LiDAR's fog function is the shared one at 905 nm.
    if (w.fog_visibility_m)
      CHECK(FogExtinctionPerM(*w.fog_visibility_m) ==
            FogExtinctionPerM(*w.fog_visibility_m, kLidarWavelengthNm));
  }
  // Rain alone: the same law, so the same number for both.
  for (double rain_mm_h : {1.0, 10.0, 25.0, 100.0}) {
    INFO("rain " << rain_mm_h << " mm/h");
    const core::WeatherConfig w = Weather(rain_mm_h);
    CHECK(CameraExtinctionPerM(w) == AtmosphericExtinctionPerM(w));
    CHECK(CameraExtinctionPerM(w) == Approx(MarshallPalmerRain(rain_mm_h)).epsilon(1e-12));
  }
  // Fog alone: Koschmieder for the camera, exactly; and dense fog (q = 0)
  // is the same for both, with rain or without.
  CHECK(CameraExtinctionPerM(Weather(0.0, 1000.0)) == 3.912 / 1000.0);
  CHECK(CameraExtinctionPerM(Weather(0.0, 300.0)) ==
        Approx(AtmosphericExtinctionPerM(Weather(0.0, 300.0))).epsilon(1e-12));
  CHECK(CameraExtinctionPerM(Weather(10.0, 300.0)) ==
        Approx(AtmosphericExtinctionPerM(Weather(10.0, 300.0))).epsilon(1e-12));
}

TEST_CASE("Atmosphere: the camera renders a wall through rain with the Marshall-Palmer law",
          "[sensors]") {
  // A dark wall straight ahead at distance_m, nothing else: the pixel on the
  // axis sees the wall, the pixel straight up sees the airlight A. Rain
  // takes the wall's radiance L to L e^(-alpha d) + A (1 - e^(-alpha d)),
  // so (A - L_rain) / (A - L_clear) = e^(-alpha d).
  FisheyeStereoConfig c;
  c.pose.position_m = {0, 0, 1.5};
  c.sensor_noise = false;
  const double distance_m = 300.0;
  core::WorldGeometry world;
  core::TriangleMesh wall;
  wall.name = "wall";
  wall.material = core::kMaterialConcrete;
  const Eigen::Vector3d center(distance_m, 0, 1.5), a(0, 150, 0), b(0, 0, 90);
  for (const Eigen::Vector3d& p :
       std::vector<Eigen::Vector3d>{center - a - b, center + a - b, center + a + b, center - a + b})
    wall.vertices_m.push_back(p.cast<float>());
  wall.triangles = {{0, 1, 2}, {0, 2, 3}};
  world.meshes = {wall};
  RaycastScene scene(world);
  FisheyeStereo camera(c, scene);
  const std::size_t axis = static_cast<std::size_t>(240) * c.width_px + 320;
  const std::size_t up = static_cast<std::size_t>(10) * c.width_px + 320;
  const double wall_clear = camera.CaptureRadiance(0.0, Weather(0.0))[axis];
  for (double rain_mm_h : {10.0, 25.0}) {
    INFO("rain " << rain_mm_h << " mm/h");
    const std::vector<float> rain = camera.CaptureRadiance(0.0, Weather(rain_mm_h));
    const double airlight = rain[up];
    const double measured = (airlight - rain[axis]) / (airlight - wall_clear);
    const double expected = std::exp(-MarshallPalmerRain(rain_mm_h) * distance_m);
    INFO("transmittance " << measured << ", Marshall-Palmer " << expected);
    CHECK(airlight - wall_clear > 0.1);  // a dark wall: the ratio is well conditioned
    CHECK(measured == Approx(expected).epsilon(2e-3));
  }
}

}  // namespace uavsim::sensors
