#include "core/trajectory.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/error.h"
#include "core/json_io.h"
#include "core/physical_constants.h"

namespace uavsim::core {
namespace {

constexpr double kMaxCoordinate_m = 1e5;
// Band of the random trajectory's sinusoid periods: slow enough to look like
// deliberate flight, fast enough that a 60 s run sees several turns.
constexpr double kRandomMinPeriod_s = 8.0;
constexpr double kRandomMaxPeriod_s = 40.0;
// Component weights are kept away from 0 so no drawn sinusoid is negligible.
constexpr double kRandomMinWeight = 0.5;
constexpr double kRandomMaxWeight = 1.5;

std::string Fmt(double x) {
  std::ostringstream s;
  s.precision(6);
  s << x;
  return s.str();
}

std::string Fmt(const Eigen::Vector3d& p) {
  return "[" + Fmt(p.x()) + ", " + Fmt(p.y()) + ", " + Fmt(p.z()) + "]";
}

// A cross-field error belongs where the user can fix it: at `primary`, unless
// the document sets only `alternative` (e.g. a too-small radius_m with the
// default speed_mps is reported at radius_m). The writer's Has() is always
// true, so it gets `primary`, and ignores the check anyway.
template <class V>
const char* Blame(const V& v, const char* primary, const char* alternative) {
  return v.Has(alternative) && !v.Has(primary) ? alternative : primary;
}

// Check() escapes '/' in its key, so a rule about one element of an array
// needs its pointer built here.
template <class V>
void CheckElement(const V& v, bool ok, const char* key, std::size_t index,
                  const std::string& message) {
  if constexpr (V::kReading) {
    if (!ok) throw ConfigError(v.file(), v.Child(key) + "/" + std::to_string(index), message);
  } else {
    (void)v, (void)ok, (void)key, (void)index, (void)message;
  }
}

// Figure-eight half extents: x = a sin(wt), y = b sin(2wt), so size_m is the
// full extent (2a, 2b).
struct Figure8Shape {
  double a_m, b_m, omega_rad_s;
};

Figure8Shape ShapeOf(const TrajectoryConfig& c) {
  return {0.5 * c.size_m.x(), 0.5 * c.size_m.y(), 2.0 * kPi / c.period_s};
}

// |v|^2 = w^2 (a^2 cos^2 wt + 4 b^2 cos^2 2wt): both cosines reach 1 at t = 0.
double Figure8PeakSpeed(const Figure8Shape& s) {
  return s.omega_rad_s * std::sqrt(s.a_m * s.a_m + 4.0 * s.b_m * s.b_m);
}

// |a|^2 = w^4 (a^2 sin^2 wt + 16 b^2 sin^2 2wt) = w^4 u (a^2 + 64 b^2 (1 - u))
// with u = sin^2 wt in [0, 1]: a concave parabola in u, so the peak is exact
// (the tests check it against dense sampling).
double Figure8PeakAccel(const Figure8Shape& s) {
  const double a2 = s.a_m * s.a_m, c = 64.0 * s.b_m * s.b_m;
  const double u_star = (a2 + c) / (2.0 * c);
  const double peak2 = u_star >= 1.0 ? a2 : (a2 + c) * (a2 + c) / (4.0 * c);
  return s.omega_rad_s * s.omega_rad_s * std::sqrt(peak2);
}

class OrbitTrajectory final : public Trajectory {
 public:
  explicit OrbitTrajectory(const TrajectoryConfig& c)
      : center_m_(c.center_m),
        radius_m_(c.radius_m),
        omega_rad_s_((c.clockwise ? -1.0 : 1.0) * c.speed_mps / c.radius_m),
        phase_rad_(c.phase_deg * kDegToRad) {}

  KinematicState StateAt(double t_s) const override {
    const double theta = phase_rad_ + omega_rad_s_ * t_s;
    const Eigen::Vector3d radial(std::cos(theta), std::sin(theta), 0.0);
    const Eigen::Vector3d tangent(-std::sin(theta), std::cos(theta), 0.0);
    KinematicState s;
    s.position_m = center_m_ + radius_m_ * radial;
    s.velocity_mps = radius_m_ * omega_rad_s_ * tangent;
    s.acceleration_mps2 = -radius_m_ * omega_rad_s_ * omega_rad_s_ * radial;
    return s;
  }

 private:
  Eigen::Vector3d center_m_;
  double radius_m_;
  double omega_rad_s_;  // signed: negative is clockwise seen from above
  double phase_rad_;
};

class Figure8Trajectory final : public Trajectory {
 public:
  explicit Figure8Trajectory(const TrajectoryConfig& c)
      : center_m_(c.center_m),
        shape_(ShapeOf(c)),
        period_s_(c.period_s),
        R_WF_(Eigen::AngleAxisd(c.heading_deg * kDegToRad, Eigen::Vector3d::UnitZ())
                  .toRotationMatrix()) {}

  KinematicState StateAt(double t_s) const override {
    // Reducing t by the period first keeps a long run's phase error at the
    // rounding of one period, not of the whole elapsed time.
    const double w = shape_.omega_rad_s;
    const double theta = w * std::fmod(t_s, period_s_);
    const double s1 = std::sin(theta), c1 = std::cos(theta);
    const double s2 = std::sin(2.0 * theta), c2 = std::cos(2.0 * theta);
    const double a = shape_.a_m, b = shape_.b_m;
    KinematicState s;
    s.position_m = center_m_ + R_WF_ * Eigen::Vector3d(a * s1, b * s2, 0.0);
    s.velocity_mps = R_WF_ * Eigen::Vector3d(a * w * c1, 2.0 * b * w * c2, 0.0);
    s.acceleration_mps2 = R_WF_ * Eigen::Vector3d(-a * w * w * s1, -4.0 * b * w * w * s2, 0.0);
    return s;
  }

 private:
  Eigen::Vector3d center_m_;
  Figure8Shape shape_;
  double period_s_;
  Eigen::Matrix3d R_WF_;  // figure frame F (its own x, y) to world W
};

class WaypointTrajectory final : public Trajectory {
 public:
  explicit WaypointTrajectory(const TrajectoryConfig& c)
      : accel_mps2_(c.max_accel_mps2), loop_(c.loop) {
    const std::size_t n = c.points_m.size();
    const std::size_t num_legs = loop_ ? n : n - 1;
    const double v = c.max_speed_mps, a = c.max_accel_mps2;
    double start_s = 0.0;
    for (std::size_t i = 0; i < num_legs; ++i) {
      Leg leg;
      leg.from_m = c.points_m[i];
      leg.to_m = c.points_m[(i + 1) % n];
      const Eigen::Vector3d delta = leg.to_m - leg.from_m;
      const double d = delta.norm();
      leg.dir = delta / d;
      leg.start_s = start_s;
      if (d >= v * v / a) {  // reaches max speed: ramp, cruise, ramp
        leg.ramp_s = v / a;
        leg.peak_speed_mps = v;
        leg.cruise_s = (d - v * v / a) / v;
      } else {  // too short to reach it: triangular profile
        leg.ramp_s = std::sqrt(d / a);
        leg.peak_speed_mps = a * leg.ramp_s;
        leg.cruise_s = 0.0;
      }
      leg.duration_s = 2.0 * leg.ramp_s + leg.cruise_s;
      start_s += leg.duration_s;
      legs_.push_back(leg);
    }
    total_s_ = start_s;
    last_m_ = c.points_m.back();
  }

  KinematicState StateAt(double t_s) const override {
    double t = std::max(t_s, 0.0);
    if (loop_) {
      t = std::fmod(t, total_s_);
    } else if (t >= total_s_) {
      KinematicState hover;
      hover.position_m = last_m_;
      return hover;
    }
    auto it = std::upper_bound(legs_.begin(), legs_.end(), t,
                               [](double x, const Leg& leg) { return x < leg.start_s; });
    const Leg& leg = *std::prev(it);  // legs_[0].start_s == 0 <= t, so it != begin
    const double tau = t - leg.start_s;
    const double a = accel_mps2_;
    double along_m, speed_mps, accel_mps2;
    KinematicState s;
    if (tau < leg.ramp_s) {
      along_m = 0.5 * a * tau * tau;
      speed_mps = a * tau;
      accel_mps2 = a;
      s.position_m = leg.from_m + along_m * leg.dir;
    } else if (tau < leg.ramp_s + leg.cruise_s) {
      along_m = 0.5 * a * leg.ramp_s * leg.ramp_s + leg.peak_speed_mps * (tau - leg.ramp_s);
      speed_mps = leg.peak_speed_mps;
      accel_mps2 = 0.0;
      s.position_m = leg.from_m + along_m * leg.dir;
    } else {
      // Measured back from the leg's end, so the UAV lands on the waypoint
      // itself rather than on from + d * dir with its rounding.
      const double remaining_s = std::max(leg.duration_s - tau, 0.0);
      speed_mps = a * remaining_s;
      accel_mps2 = -a;
      s.position_m = leg.to_m - (0.5 * a * remaining_s * remaining_s) * leg.dir;
    }
    s.velocity_mps = speed_mps * leg.dir;
    s.acceleration_mps2 = accel_mps2 * leg.dir;
    return s;
  }

 private:
  struct Leg {
    Eigen::Vector3d from_m, to_m;
    Eigen::Vector3d dir;  // unit vector from_m -> to_m
    double start_s = 0.0;
    double ramp_s = 0.0;  // duration of each of the speed-up and slow-down ramps
    double cruise_s = 0.0;
    double duration_s = 0.0;
    double peak_speed_mps = 0.0;
  };

  std::vector<Leg> legs_;
  double accel_mps2_;
  bool loop_;
  double total_s_ = 0.0;
  Eigen::Vector3d last_m_;
};

class RandomTrajectory final : public Trajectory {
 public:
  RandomTrajectory(const TrajectoryConfig& c, RngStream& rng) {
    // Per-axis bounds: |v_k| <= max_speed/sqrt(3) on each of the three axes
    // keeps |v| <= max_speed (same for acceleration); sum |A_i| bounds the
    // excursion from the box centre.
    const double speed_bound = c.max_speed_mps / std::sqrt(3.0);
    const double accel_bound = c.max_accel_mps2 / std::sqrt(3.0);
    for (int k = 0; k < 3; ++k) {
      Axis& axis = axes_[k];
      axis.center_m = 0.5 * (c.min_m[k] + c.max_m[k]);
      const double half_extent_m = 0.5 * (c.max_m[k] - c.min_m[k]);
      double sum_w = 0.0, sum_w_omega = 0.0, sum_w_omega2 = 0.0;
      for (int i = 0; i < c.components; ++i) {
        Component comp;
        const double period_s = rng.Uniform(kRandomMinPeriod_s, kRandomMaxPeriod_s);
        comp.omega_rad_s = 2.0 * kPi / period_s;
        comp.phase_rad = rng.Uniform(0.0, 2.0 * kPi);
        comp.amplitude_m = rng.Uniform(kRandomMinWeight, kRandomMaxWeight);  // weight for now
        sum_w += comp.amplitude_m;
        sum_w_omega += comp.amplitude_m * comp.omega_rad_s;
        sum_w_omega2 += comp.amplitude_m * comp.omega_rad_s * comp.omega_rad_s;
        axis.components.push_back(comp);
      }
      const double scale =
          std::min({half_extent_m / sum_w, speed_bound / sum_w_omega, accel_bound / sum_w_omega2});
      for (Component& comp : axis.components) comp.amplitude_m *= scale;
    }
  }

  KinematicState StateAt(double t_s) const override {
    KinematicState s;
    for (int k = 0; k < 3; ++k) {
      double p = axes_[k].center_m, v = 0.0, a = 0.0;
      for (const Component& comp : axes_[k].components) {
        const double theta = comp.omega_rad_s * t_s + comp.phase_rad;
        const double sn = std::sin(theta), cs = std::cos(theta);
        p += comp.amplitude_m * sn;
        v += comp.amplitude_m * comp.omega_rad_s * cs;
        a -= comp.amplitude_m * comp.omega_rad_s * comp.omega_rad_s * sn;
      }
      s.position_m[k] = p;
      s.velocity_mps[k] = v;
      s.acceleration_mps2[k] = a;
    }
    return s;
  }

 private:
  struct Component {
    double amplitude_m = 0.0;
    double omega_rad_s = 0.0;
    double phase_rad = 0.0;
  };
  struct Axis {
    double center_m = 0.0;
    std::vector<Component> components;
  };
  std::array<Axis, 3> axes_;
};

}  // namespace

template <class V>
void Visit(V& v, TrajectoryConfig& c) {
  v.Enum("type", c.type,
         {{"waypoints", TrajectoryType::kWaypoints},
          {"orbit", TrajectoryType::kOrbit},
          {"figure8", TrajectoryType::kFigure8},
          {"random", TrajectoryType::kRandom}});
  v("max_speed_mps", c.max_speed_mps, Rule::Positive(200.0));
  v("max_accel_mps2", c.max_accel_mps2, Rule::Positive(100.0));
  const Rule coordinate = Rule::Range(-kMaxCoordinate_m, kMaxCoordinate_m);
  const Rule angle = Rule::Range(-360.0, 360.0);

  // Only the chosen type's keys are asked for, so the reader reports any
  // other type's key as unknown instead of ignoring it.
  switch (c.type) {
    case TrajectoryType::kOrbit: {
      v("center_m", c.center_m, coordinate);
      v("radius_m", c.radius_m, Rule::Positive(kMaxCoordinate_m));
      v("speed_mps", c.speed_mps, Rule::Positive(200.0));
      v("clockwise", c.clockwise);
      v("phase_deg", c.phase_deg, angle);
      v.Check(c.speed_mps <= c.max_speed_mps, Blame(v, "speed_mps", "max_speed_mps"),
              "speed_mps (" + Fmt(c.speed_mps) + ") exceeds max_speed_mps (" +
                  Fmt(c.max_speed_mps) + ")");
      const double centripetal_mps2 = c.speed_mps * c.speed_mps / c.radius_m;
      v.Check(centripetal_mps2 <= c.max_accel_mps2, Blame(v, "radius_m", "speed_mps"),
              "centripetal acceleration speed_mps^2/radius_m = " + Fmt(centripetal_mps2) +
                  " m/s^2 exceeds max_accel_mps2 (" + Fmt(c.max_accel_mps2) +
                  "); raise radius_m or lower speed_mps");
      break;
    }
    case TrajectoryType::kFigure8: {
      v("center_m", c.center_m, coordinate);
      v("size_m", c.size_m, Rule::Positive(2.0 * kMaxCoordinate_m));
      v("period_s", c.period_s, Rule::Positive(1e6));
      v("heading_deg", c.heading_deg, angle);
      const Figure8Shape shape = ShapeOf(c);
      const double peak_speed_mps = Figure8PeakSpeed(shape);
      const double peak_accel_mps2 = Figure8PeakAccel(shape);
      v.Check(peak_speed_mps <= c.max_speed_mps, Blame(v, "period_s", "size_m"),
              "peak speed (2*pi/period_s)*sqrt((size_m[0]/2)^2 + size_m[1]^2) = " +
                  Fmt(peak_speed_mps) + " m/s exceeds max_speed_mps (" + Fmt(c.max_speed_mps) +
                  "); lengthen period_s or shrink size_m");
      v.Check(peak_accel_mps2 <= c.max_accel_mps2, Blame(v, "period_s", "size_m"),
              "peak acceleration of the figure eight = " + Fmt(peak_accel_mps2) +
                  " m/s^2 exceeds max_accel_mps2 (" + Fmt(c.max_accel_mps2) +
                  "); lengthen period_s or shrink size_m");
      break;
    }
    case TrajectoryType::kWaypoints: {
      v("points_m", c.points_m, coordinate, 2, 10000);
      v("loop", c.loop);
      // A zero-length leg has no direction to fly along.
      const std::size_t n = c.points_m.size();
      for (std::size_t i = 1; i < n; ++i)
        CheckElement(v, c.points_m[i] != c.points_m[i - 1], "points_m", i,
                     "point " + std::to_string(i) + " " + Fmt(c.points_m[i]) + " repeats point " +
                         std::to_string(i - 1) + "; consecutive waypoints must differ");
      if (c.loop && n >= 2)
        CheckElement(v, c.points_m[n - 1] != c.points_m[0], "points_m", n - 1,
                     "point " + std::to_string(n - 1) + " " + Fmt(c.points_m[n - 1]) +
                         " repeats point 0 while loop is true; the loop returns to point 0 by "
                         "itself, so drop the last point");
      break;
    }
    case TrajectoryType::kRandom: {
      v("min_m", c.min_m, coordinate);
      v("max_m", c.max_m, coordinate);
      v("components", c.components, Rule::Range(1, 16));
      static const char* const kAxis[] = {"x", "y", "z"};
      for (int k = 0; k < 3; ++k)
        CheckElement(v, c.min_m[k] < c.max_m[k], Blame(v, "max_m", "min_m"),
                     static_cast<std::size_t>(k),
                     std::string("min_m[") + std::to_string(k) + "] (" + Fmt(c.min_m[k]) +
                         ") must be less than max_m[" + std::to_string(k) + "] (" +
                         Fmt(c.max_m[k]) + "): the box is empty along " + kAxis[k]);
      break;
    }
  }
}
UAVSIM_INSTANTIATE_VISIT(TrajectoryConfig);

std::unique_ptr<Trajectory> MakeTrajectory(const TrajectoryConfig& config, RngStream rng) {
  // Validation is the reader's Visit, run over the config's own JSON, so a
  // config built in code meets exactly the rules `uavsim validate` applies.
  try {
    TrajectoryConfig checked;
    FromJson(ToJson(config), "TrajectoryConfig", "", checked);
  } catch (const ConfigError& e) {
    throw std::invalid_argument(std::string("MakeTrajectory: invalid config: ") + e.what());
  }
  switch (config.type) {
    case TrajectoryType::kOrbit:
      return std::make_unique<OrbitTrajectory>(config);
    case TrajectoryType::kFigure8:
      return std::make_unique<Figure8Trajectory>(config);
    case TrajectoryType::kWaypoints:
      return std::make_unique<WaypointTrajectory>(config);
    case TrajectoryType::kRandom:
      return std::make_unique<RandomTrajectory>(config, rng);
  }
  throw std::invalid_argument("MakeTrajectory: unknown trajectory type " +
                              std::to_string(static_cast<int>(config.type)));
}

}  // namespace uavsim::core
