#include "core/trajectory.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/json_io.h"
#include "core/rng.h"

namespace uavsim::core {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHorizon_s = 300.0;
constexpr double kStep_s = 0.01;
constexpr double kLimitTol = 1e-9;
// Central-difference step: truncation error h^2/6 |d3x/dt3| stays below 1e-7
// for these trajectories while rounding (eps |x| / h) stays near 1e-11.
constexpr double kFdStep_s = 1e-3;
constexpr double kFdTol = 1e-6;

TrajectoryConfig Parse(const Json& j) {
  TrajectoryConfig c;
  FromJson(j, "t.json", "/trajectory", c);
  return c;
}

// what() of the ConfigError the reader throws for `j`, or "" if none.
std::string ConfigErrorOf(const Json& j) {
  try {
    Parse(j);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// Times near which acceleration may jump (where finite differences do not
// apply); `periodic` reduces t modulo `period_s` first.
struct Discontinuities {
  std::vector<double> times_s;
  double period_s = 0.0;
  bool Near(double t_s, double margin_s) const {
    double t = period_s > 0.0 ? std::fmod(t_s, period_s) : t_s;
    for (double ts : times_s) {
      if (std::abs(t - ts) < margin_s) return true;
      if (period_s > 0.0 && std::abs(t - ts - period_s) < margin_s) return true;
      if (period_s > 0.0 && std::abs(t - ts + period_s) < margin_s) return true;
    }
    return false;
  }
};

// Limits and closed-form derivatives, sampled every 10 ms over 300 s.
void CheckKinematics(const Trajectory& traj, const TrajectoryConfig& c,
                     const Discontinuities& jumps = {}) {
  const double h = kFdStep_s;
  double worst_speed = 0.0, worst_accel = 0.0, worst_fd_v = 0.0, worst_fd_a = 0.0;
  for (int i = 1; i * kStep_s <= kHorizon_s; ++i) {
    const double t = i * kStep_s;
    const KinematicState s = traj.StateAt(t);
    worst_speed = std::max(worst_speed, s.velocity_mps.norm());
    worst_accel = std::max(worst_accel, s.acceleration_mps2.norm());
    if (jumps.Near(t, 2.0 * h)) continue;
    const KinematicState before = traj.StateAt(t - h), after = traj.StateAt(t + h);
    const Eigen::Vector3d fd_v = (after.position_m - before.position_m) / (2.0 * h);
    const Eigen::Vector3d fd_a = (after.velocity_mps - before.velocity_mps) / (2.0 * h);
    worst_fd_v = std::max(worst_fd_v, (fd_v - s.velocity_mps).norm());
    worst_fd_a = std::max(worst_fd_a, (fd_a - s.acceleration_mps2).norm());
  }
  CHECK(worst_speed <= c.max_speed_mps + kLimitTol);
  CHECK(worst_accel <= c.max_accel_mps2 + kLimitTol);
  CHECK(worst_fd_v <= kFdTol);
  CHECK(worst_fd_a <= kFdTol);
}

// Independent trapezoid: time to cover d from rest to rest.
double LegDuration(double d, double v, double a) {
  return d >= v * v / a ? d / v + v / a : 2.0 * std::sqrt(d / a);
}
double RampDuration(double d, double v, double a) { return std::min(v / a, std::sqrt(d / a)); }

struct LegTimes {
  std::vector<double> end_s;  // end of leg i (arrival at waypoint i + 1)
  Discontinuities jumps;
};

LegTimes ExpectedLegTimes(const TrajectoryConfig& c) {
  const std::size_t n = c.points_m.size();
  const std::size_t legs = c.loop ? n : n - 1;
  LegTimes out;
  double t = 0.0;
  for (std::size_t i = 0; i < legs; ++i) {
    const double d = (c.points_m[(i + 1) % n] - c.points_m[i]).norm();
    const double dur = LegDuration(d, c.max_speed_mps, c.max_accel_mps2);
    const double ramp = RampDuration(d, c.max_speed_mps, c.max_accel_mps2);
    out.jumps.times_s.insert(out.jumps.times_s.end(), {t, t + ramp, t + dur - ramp});
    t += dur;
    out.end_s.push_back(t);
  }
  out.jumps.times_s.push_back(t);
  if (c.loop) out.jumps.period_s = t;
  return out;
}

void CheckPassesEveryWaypoint(const Trajectory& traj, const TrajectoryConfig& c) {
  const LegTimes times = ExpectedLegTimes(c);
  const std::size_t n = c.points_m.size();
  const double a = c.max_accel_mps2;
  for (std::size_t i = 0; i < times.end_s.size(); ++i) {
    const Eigen::Vector3d& target = c.points_m[(i + 1) % n];
    const double t_end = times.end_s[i];
    const double t_start = i == 0 ? 0.0 : times.end_s[i - 1];
    INFO("leg " << i << " ends at " << t_end << " s");
    // Arrives at the end of the analytic duration, at rest...
    const KinematicState at_end = traj.StateAt(t_end);
    CHECK((at_end.position_m - target).norm() <= 1e-9);
    CHECK(at_end.velocity_mps.norm() <= 1e-9);
    const KinematicState just_before = traj.StateAt(t_end - 1e-9);
    CHECK((just_before.position_m - target).norm() <= 1e-9);
    // ...and not earlier: the last ramp slows down at exactly max_accel, so
    // speed 0.1 s before the end tells the end time to rounding.
    const double ramp = RampDuration((target - c.points_m[i]).norm(), c.max_speed_mps, a);
    const double back_s = std::min(0.1, 0.5 * ramp);
    CHECK(std::abs(traj.StateAt(t_end - back_s).velocity_mps.norm() - a * back_s) <= 1e-9);
    // Peak speed mid-leg: max_speed on a trapezoid, sqrt(d a) on a triangle.
    const double d = (target - c.points_m[i]).norm();
    const double peak = std::min(c.max_speed_mps, std::sqrt(d * a));
    CHECK(std::abs(traj.StateAt(0.5 * (t_start + t_end)).velocity_mps.norm() - peak) <= 1e-9);
    // Straight along the leg: the midpoint of the leg in time is the midpoint in space.
    const Eigen::Vector3d mid = 0.5 * (c.points_m[i] + target);
    CHECK((traj.StateAt(0.5 * (t_start + t_end)).position_m - mid).norm() <= 1e-9);
  }
  // Velocity is continuous across every phase switch (acceleration may jump).
  for (double ts : times.jumps.times_s) {
    if (ts <= 1e-6) continue;
    const KinematicState l = traj.StateAt(ts - 1e-9), r = traj.StateAt(ts + 1e-9);
    CHECK((l.velocity_mps - r.velocity_mps).norm() <= 1e-7);
    CHECK((l.position_m - r.position_m).norm() <= 1e-7);
  }
}

bool SameState(const KinematicState& x, const KinematicState& y, double tol) {
  return (x.position_m - y.position_m).norm() <= tol &&
         (x.velocity_mps - y.velocity_mps).norm() <= tol &&
         (x.acceleration_mps2 - y.acceleration_mps2).norm() <= tol;
}

TEST_CASE("Trajectory: orbit is a circle at constant speed", "[core]") {
  TrajectoryConfig c;
  c.type = TrajectoryType::kOrbit;
  c.center_m = {10.0, -5.0, 40.0};
  c.radius_m = 30.0;
  c.speed_mps = 9.0;
  c.phase_deg = 45.0;
  const bool clockwise = GENERATE(false, true);
  c.clockwise = clockwise;
  const auto traj = MakeTrajectory(c, RngStream(1, "unused"));
  CheckKinematics(*traj, c);

  const double period_s = 2.0 * kPi * c.radius_m / c.speed_mps;
  const KinematicState s0 = traj->StateAt(0.0);
  const Eigen::Vector3d start =
      c.center_m + c.radius_m * Eigen::Vector3d(std::cos(kPi / 4), std::sin(kPi / 4), 0.0);
  CHECK((s0.position_m - start).norm() <= 1e-9);
  for (double t = 0.0; t <= kHorizon_s; t += 0.37) {
    const KinematicState s = traj->StateAt(t);
    const Eigen::Vector3d rel = s.position_m - c.center_m;
    CHECK(std::abs(rel.norm() - c.radius_m) <= 1e-9);
    CHECK(std::abs(rel.z()) <= 1e-12);
    CHECK(std::abs(s.velocity_mps.norm() - c.speed_mps) <= 1e-9);
    CHECK(std::abs(s.acceleration_mps2.norm() - c.speed_mps * c.speed_mps / c.radius_m) <= 1e-9);
    // Sense of rotation from the angular momentum about +z.
    CHECK((rel.x() * s.velocity_mps.y() - rel.y() * s.velocity_mps.x() < 0.0) == clockwise);
    CHECK(SameState(traj->StateAt(t + period_s), s, 1e-8));
  }
  CHECK((traj->StateAt(0.5 * period_s).position_m - (2.0 * c.center_m - start)).norm() <= 1e-8);
}

TEST_CASE("Trajectory: figure8 is a periodic Gerono lemniscate of the configured size", "[core]") {
  TrajectoryConfig c;
  c.type = TrajectoryType::kFigure8;
  c.center_m = {5.0, 5.0, 35.0};
  c.size_m = {60.0, 20.0};
  c.period_s = 37.0;
  c.heading_deg = 30.0;
  const auto traj = MakeTrajectory(c, RngStream(1, "unused"));
  CheckKinematics(*traj, c);

  const Eigen::Matrix3d R_FW =
      Eigen::AngleAxisd(-30.0 * kPi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  CHECK((traj->StateAt(0.0).position_m - c.center_m).norm() <= 1e-12);
  CHECK(SameState(traj->StateAt(c.period_s), traj->StateAt(0.0), 1e-9));
  double max_x = 0.0, max_y = 0.0;
  for (double t = 0.0; t <= kHorizon_s; t += 0.01) {
    const KinematicState s = traj->StateAt(t);
    const Eigen::Vector3d p_F = R_FW * (s.position_m - c.center_m);
    CHECK(std::abs(p_F.z()) <= 1e-12);
    max_x = std::max(max_x, std::abs(p_F.x()));
    max_y = std::max(max_y, std::abs(p_F.y()));
    // Gerono: (x/a)^4 = (x/a)^2 - (y/b)^2 with x = a sin wt, y = b sin 2wt.
    const double xa = p_F.x() / 30.0, yb = p_F.y() / 10.0;
    CHECK(std::abs(4.0 * (xa * xa - xa * xa * xa * xa) - yb * yb) <= 1e-9);
  }
  CHECK(max_x == Approx(30.0).epsilon(1e-5));
  CHECK(max_y == Approx(10.0).epsilon(1e-5));
  for (double t = 0.3; t < 100.0; t += 7.1)
    CHECK(SameState(traj->StateAt(t + c.period_s), traj->StateAt(t), 1e-9));
}

TEST_CASE("Trajectory: figure8 validation refuses exactly the sampled peaks over the limits",
          "[core]") {
  // Sample peaks of a generously limited figure eight, then put the limits
  // just above and just below them: validation must agree with sampling.
  // The second shape has its acceleration peak at the ends of the lobes
  // (sin^2 wt = 1), the first in between.
  const std::pair<double, double> size =
      GENERATE(std::make_pair(40.0, 36.0), std::make_pair(80.0, 4.0));
  const Json j = {{"type", "figure8"},
                  {"size_m", {size.first, size.second}},
                  {"period_s", 30.0},
                  {"max_speed_mps", 200.0},
                  {"max_accel_mps2", 100.0}};
  const TrajectoryConfig loose = Parse(j);
  const auto traj = MakeTrajectory(loose, RngStream(1, "unused"));
  double peak_speed = 0.0, peak_accel = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const KinematicState s = traj->StateAt(loose.period_s * i / 200000.0);
    peak_speed = std::max(peak_speed, s.velocity_mps.norm());
    peak_accel = std::max(peak_accel, s.acceleration_mps2.norm());
  }
  INFO("sampled peaks " << peak_speed << " m/s, " << peak_accel << " m/s^2");
  Json ok = j;
  ok["max_speed_mps"] = peak_speed * (1 + 1e-6);
  ok["max_accel_mps2"] = peak_accel * (1 + 1e-6);
  CHECK_NOTHROW(Parse(ok));
  Json fast = ok;
  fast["max_speed_mps"] = peak_speed * (1 - 1e-6);
  const std::string speed_error = ConfigErrorOf(fast);
  CHECK_THAT(speed_error, Catch::Contains("t.json: /trajectory/period_s: peak speed") &&
                              Catch::Contains("exceeds max_speed_mps"));
  Json hard = ok;
  hard["max_accel_mps2"] = peak_accel * (1 - 1e-6);
  const std::string accel_error = ConfigErrorOf(hard);
  CHECK_THAT(accel_error, Catch::Contains("t.json: /trajectory/period_s: peak acceleration") &&
                              Catch::Contains("exceeds max_accel_mps2"));
}

TEST_CASE("Trajectory: waypoints loop passes every point at the trapezoid times", "[core]") {
  TrajectoryConfig c;  // default points: legs of 40.3, 25.5, 40.3, 25.5 m > v^2/a = 20 m
  c.type = TrajectoryType::kWaypoints;
  c.points_m.push_back({-20.0, 5.0, 28.0});  // a short leg: triangular profile
  c.loop = true;
  const auto traj = MakeTrajectory(c, RngStream(1, "unused"));
  const LegTimes times = ExpectedLegTimes(c);
  CheckKinematics(*traj, c, times.jumps);
  CheckPassesEveryWaypoint(*traj, c);

  const double period_s = times.end_s.back();
  CHECK((traj->StateAt(period_s).position_m - c.points_m[0]).norm() <= 1e-9);
  for (double t = 0.05; t < 2.0 * period_s; t += 3.3)
    CHECK(SameState(traj->StateAt(t + period_s), traj->StateAt(t), 1e-7));
}

TEST_CASE("Trajectory: waypoints without loop stop and hover at the last point", "[core]") {
  TrajectoryConfig c;
  c.type = TrajectoryType::kWaypoints;
  c.loop = false;
  c.max_speed_mps = 12.0;
  c.max_accel_mps2 = 3.0;
  c.points_m = {{0, 0, 10}, {3, 0, 10}, {3, 4, 10}, {150, 4, 60}, {150.5, 4, 60}};
  const auto traj = MakeTrajectory(c, RngStream(1, "unused"));
  const LegTimes times = ExpectedLegTimes(c);
  CheckKinematics(*traj, c, times.jumps);
  CheckPassesEveryWaypoint(*traj, c);

  const double end_s = times.end_s.back();
  CHECK(traj->StateAt(end_s - 0.01).velocity_mps.norm() > 0.0);
  for (double t : {end_s, end_s + 1.0, end_s + 1e4}) {
    const KinematicState s = traj->StateAt(t);
    CHECK((s.position_m - c.points_m.back()).norm() == 0.0);
    CHECK(s.velocity_mps.norm() == 0.0);
    CHECK(s.acceleration_mps2.norm() == 0.0);
  }
}

TEST_CASE("Trajectory: random stays in its box within the limits, seeded", "[core]") {
  TrajectoryConfig c;
  c.type = TrajectoryType::kRandom;
  SECTION("default box") {}
  SECTION("small box, loose limits (position-bound)") {
    c.min_m = {-2.0, -1.0, 20.0};
    c.max_m = {2.0, 1.0, 21.0};
    c.max_speed_mps = 50.0;
    c.max_accel_mps2 = 50.0;
  }
  SECTION("large box, tight limits, many components") {
    c.min_m = {-2000.0, -2000.0, 10.0};
    c.max_m = {2000.0, 2000.0, 500.0};
    c.max_speed_mps = 3.0;
    c.max_accel_mps2 = 0.2;
    c.components = 16;
  }
  SECTION("one component") { c.components = 1; }
  const auto traj = MakeTrajectory(c, RngStream(7, "uav/target"));
  CheckKinematics(*traj, c);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (double t = 0.0; t <= kHorizon_s; t += kStep_s) {
    const Eigen::Vector3d p = traj->StateAt(t).position_m;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  for (int k = 0; k < 3; ++k) {
    CHECK(lo[k] >= c.min_m[k] - 1e-9);
    CHECK(hi[k] <= c.max_m[k] + 1e-9);
    CHECK(hi[k] > lo[k]);  // it does move along every axis
  }

  const auto same = MakeTrajectory(c, RngStream(7, "uav/target"));
  const auto other = MakeTrajectory(c, RngStream(8, "uav/target"));
  bool differs = false;
  for (double t = 0.0; t <= 60.0; t += 0.7) {
    const KinematicState a = traj->StateAt(t), b = same->StateAt(t), o = other->StateAt(t);
    CHECK(a.position_m == b.position_m);
    CHECK(a.velocity_mps == b.velocity_mps);
    CHECK(a.acceleration_mps2 == b.acceleration_mps2);
    differs = differs || (a.position_m - o.position_m).norm() > 1e-3;
  }
  CHECK(differs);
}

TEST_CASE("Trajectory: a key of another type is an unknown key", "[core]") {
  const std::string err = ConfigErrorOf(Json{{"type", "figure8"}, {"radius_m", 5.0}});
  CHECK_THAT(err, Catch::Contains("t.json: /trajectory/radius_m: unknown key"));
  CHECK_THAT(ConfigErrorOf(Json{{"type", "orbit"}, {"points_m", Json::array()}}),
             Catch::Contains("/trajectory/points_m: unknown key"));
  CHECK_THAT(ConfigErrorOf(Json{{"type", "spiral"}}),
             Catch::Contains("/trajectory/type: expected one of \"waypoints\", \"orbit\", "
                             "\"figure8\", \"random\", got \"spiral\""));
}

TEST_CASE("Trajectory: cross-field rules name the values, the rule and the pointer", "[core]") {
  CHECK_THAT(ConfigErrorOf(Json{{"type", "orbit"}, {"speed_mps", 12.0}}),
             Catch::Contains("t.json: /trajectory/speed_mps: speed_mps (12) exceeds "
                             "max_speed_mps (10)"));
  CHECK_THAT(ConfigErrorOf(Json{{"type", "orbit"}, {"max_speed_mps", 5.0}}),
             Catch::Contains("/trajectory/max_speed_mps: speed_mps (6) exceeds max_speed_mps (5)"));
  CHECK_THAT(ConfigErrorOf(Json{{"type", "orbit"}, {"radius_m", 5.0}}),
             Catch::Contains("/trajectory/radius_m: centripetal acceleration speed_mps^2/radius_m "
                             "= 7.2 m/s^2 exceeds max_accel_mps2 (5)"));
  CHECK_THAT(ConfigErrorOf(Json{{"type", "figure8"}, {"period_s", 5.0}}),
             Catch::Contains("/trajectory/period_s: peak speed") &&
                 Catch::Contains("exceeds max_speed_mps (10)"));
  CHECK_THAT(ConfigErrorOf(Json{{"type", "waypoints"},
                                {"points_m", {{0, 0, 10}, {1, 0, 10}, {1, 0, 10}, {2, 0, 10}}}}),
             Catch::Contains("/trajectory/points_m/2: point 2 [1, 0, 10] repeats point 1"));
  CHECK_THAT(ConfigErrorOf(
                 Json{{"type", "waypoints"}, {"points_m", {{0, 0, 10}, {1, 0, 10}, {0, 0, 10}}}}),
             Catch::Contains("/trajectory/points_m/2: point 2 [0, 0, 10] repeats point 0 while "
                             "loop is true"));
  CHECK(ConfigErrorOf(Json{{"type", "waypoints"},
                           {"loop", false},
                           {"points_m", {{0, 0, 10}, {1, 0, 10}, {0, 0, 10}}}})
            .empty());
  CHECK_THAT(ConfigErrorOf(Json{{"type", "waypoints"}, {"points_m", {{0, 0, 10}}}}),
             Catch::Contains("/trajectory/points_m: expected an array of at least 2 elements"));
  CHECK_THAT(ConfigErrorOf(Json{{"type", "random"}, {"max_m", {30, 30, 15}}}),
             Catch::Contains("/trajectory/max_m/2: min_m[2] (15) must be less than max_m[2] (15)"));
  CHECK_THAT(ConfigErrorOf(Json{{"type", "random"}, {"components", 17}}),
             Catch::Contains("/trajectory/components: expected an integer in [1, 16], got 17"));
  CHECK_THAT(ConfigErrorOf(Json{{"max_speed_mps", 0}}),
             Catch::Contains("/trajectory/max_speed_mps: expected a number in (0, 200], got 0"));
}

TEST_CASE("Trajectory: MakeTrajectory refuses an invalid config", "[core]") {
  TrajectoryConfig c;
  c.speed_mps = 12.0;  // default orbit, default max_speed_mps 10
  CHECK_THROWS_AS(MakeTrajectory(c, RngStream(1, "x")), std::invalid_argument);
  CHECK_THROWS_WITH(MakeTrajectory(c, RngStream(1, "x")),
                    Catch::Contains("/speed_mps: speed_mps (12) exceeds max_speed_mps (10)"));
  c.speed_mps = std::nan("");
  CHECK_THROWS_AS(MakeTrajectory(c, RngStream(1, "x")), std::invalid_argument);
  TrajectoryConfig w;
  w.type = TrajectoryType::kWaypoints;
  w.points_m = {{0, 0, 0}};
  CHECK_THROWS_AS(MakeTrajectory(w, RngStream(1, "x")), std::invalid_argument);
}

TEST_CASE("Trajectory: JsonWriter round trip keeps every value of each type", "[core]") {
  TrajectoryConfig c;
  c.max_speed_mps = 17.5;
  c.max_accel_mps2 = 6.25;
  SECTION("orbit") {
    c.type = TrajectoryType::kOrbit;
    c.center_m = {1.5, -2.25, 33.0};
    c.radius_m = 41.0;
    c.speed_mps = 11.0;
    c.clockwise = true;
    c.phase_deg = -90.0;
  }
  SECTION("figure8") {
    c.type = TrajectoryType::kFigure8;
    c.center_m = {-7.0, 3.0, 25.0};
    c.size_m = {70.0, 22.0};
    c.period_s = 55.5;
    c.heading_deg = 123.0;
  }
  SECTION("waypoints") {
    c.type = TrajectoryType::kWaypoints;
    c.points_m = {{0.1, 0.2, 0.3}, {10, 20, 30}, {-5, 7, 12}};
    c.loop = false;
  }
  SECTION("random") {
    c.type = TrajectoryType::kRandom;
    c.min_m = {-11, -12, 13};
    c.max_m = {11, 12, 14};
    c.components = 9;
  }
  const Json j = ToJson(c);
  const TrajectoryConfig back = Parse(j);
  CHECK(ToJson(back) == j);
  CHECK(back.type == c.type);
  CHECK(back.max_speed_mps == c.max_speed_mps);
  CHECK(back.max_accel_mps2 == c.max_accel_mps2);
  switch (c.type) {
    case TrajectoryType::kOrbit:
      CHECK(back.center_m == c.center_m);
      CHECK(back.radius_m == c.radius_m);
      CHECK(back.speed_mps == c.speed_mps);
      CHECK(back.clockwise == c.clockwise);
      CHECK(back.phase_deg == c.phase_deg);
      CHECK(!j.contains("points_m"));
      CHECK(!j.contains("size_m"));
      break;
    case TrajectoryType::kFigure8:
      CHECK(back.center_m == c.center_m);
      CHECK(back.size_m == c.size_m);
      CHECK(back.period_s == c.period_s);
      CHECK(back.heading_deg == c.heading_deg);
      CHECK(!j.contains("radius_m"));
      break;
    case TrajectoryType::kWaypoints:
      CHECK(back.points_m == c.points_m);
      CHECK(back.loop == c.loop);
      CHECK(!j.contains("center_m"));
      break;
    case TrajectoryType::kRandom:
      CHECK(back.min_m == c.min_m);
      CHECK(back.max_m == c.max_m);
      CHECK(back.components == c.components);
      CHECK(!j.contains("center_m"));
      break;
  }
  CHECK(j.begin().key() == "type");
}

}  // namespace
}  // namespace uavsim::core
