#include "sensors/fisheye_stereo.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/counter_normal.h"
#include "core/physical_constants.h"
#include "sensors/atmosphere.h"

namespace uavsim::sensors {
namespace {

using core::kPi;

// Radiometry in units of the 8-bit full scale at exposure 1. A white
// surface facing a 45-degree sun would sit just above full scale, so the
// sunlit 0.35-albedo concrete of the city lands mid-grey and the sky a bit
// brighter, as an auto-exposed daytime camera shows them.
constexpr double kSunRadiance = 0.9;       // white Lambertian surface facing the sun
constexpr double kSkyAmbient = 0.45;       // white surface under the whole sky (mean sky radiance)
constexpr double kGroundAlbedo = 0.15;     // what down-facing surfaces see (ground bounce)
constexpr double kSkyZenith = 0.35;        // blue zenith: darker than the horizon
constexpr double kSkyHorizon = 0.75;       // hazy horizon; also the airlight of fog and rain
constexpr double kStreakBrightness = 1.3;  // a drop refracts the bright sky: streaks x airlight

// The spheres of moving objects are widened by this much before deciding
// which packets to re-cast: far more than the float rounding of the meshes,
// the instance transforms and the rays (about 1e-7 relative).
constexpr double kSphereMarginRel = 0.01;
constexpr double kSphereMargin_m = 0.01;
// The packets' cones are widened by this much (radians).
constexpr double kPacketConeMargin_rad = 1e-6;
// An eye closer than this to the static world's bounds renders every pixel.
constexpr double kStaticBoundsMargin_m = 0.01;

// Sky radiance by elevation: a vertical gradient from the bright horizon
// to the darker zenith. Below the horizon (past the edge of the ground
// plane) the horizon value continues.
double SkyRadiance(double direction_z) {
  const double s = 1.0 - std::clamp(direction_z, 0.0, 1.0);
  return kSkyZenith + (kSkyHorizon - kSkyZenith) * s * s;
}

}  // namespace

struct FisheyeStereo::Light {
  double gain = 1.0;
  double beta_per_m = 0.0;  // extinction of fog and rain together
  double airlight = 0.0;    // radiance of the scattering medium, gain included
  bool Same(const Light& o) const {
    return gain == o.gain && beta_per_m == o.beta_per_m && airlight == o.airlight;
  }
};

struct FisheyeStereo::Cache {
  bool built = false;
  Light light;                      // the light the radiance was computed under
  bool usable[2] = {false, false};  // the eye's centre is inside the static world's bounds
  std::vector<float> radiance[2];   // per valid pixel, row-major (as direction_W_)
  std::size_t last_capture_rays = 0;
};

struct FisheyeStereo::Streak {
  double u0, v0, v1;  // top point and bottom row, pixels
  double du_dv;       // slant
  double alpha;       // opacity
};

FisheyeStereo::FisheyeStereo(const FisheyeStereoConfig& config, const RaycastScene& scene)
    : config_(config), scene_(scene), model_(config), table_(model_.ComputeRayTable()) {
  X_WC_[0] = config_.pose.ToIsometry();
  X_WC_[0].linear() = X_WC_[0].linear() * R_BC();
  X_WC_[1] = X_WC_[0] * Eigen::Translation3d(config_.baseline_m, 0.0, 0.0);

  const int w = table_.width_px, h = table_.height_px;
  const Eigen::Matrix3f R_WC = X_WC_[0].linear().cast<float>();
  row_begin_.reserve(h + 1);
  direction_W_.reserve(table_.valid_count);
  column_.reserve(table_.valid_count);
  for (int v = 0; v < h; ++v) {
    row_begin_.push_back(static_cast<std::uint32_t>(direction_W_.size()));
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      if (!table_.valid[i]) continue;
      direction_W_.push_back((R_WC * table_.direction_C[i]).normalized());
      column_.push_back(static_cast<std::uint16_t>(u));
    }
  }
  row_begin_.push_back(static_cast<std::uint32_t>(direction_W_.size()));

  packet_begin_.reserve(h + 1);
  for (int v = 0; v < h; ++v) {
    packet_begin_.push_back(static_cast<std::uint32_t>(packets_.size()));
    for (std::uint32_t first = row_begin_[v]; first < row_begin_[v + 1]; first += 8) {
      const std::uint32_t end = std::min(first + 8, row_begin_[v + 1]);
      Eigen::Vector3d axis = Eigen::Vector3d::Zero();
      for (std::uint32_t i = first; i < end; ++i)
        axis += direction_W_[i].cast<double>().normalized();
      axis.normalize();
      double half_angle_rad = 0.0;
      for (std::uint32_t i = first; i < end; ++i) {
        const Eigen::Vector3d d = direction_W_[i].cast<double>().normalized();
        half_angle_rad = std::max(half_angle_rad, std::atan2(axis.cross(d).norm(), axis.dot(d)));
      }
      half_angle_rad = std::min(half_angle_rad + kPacketConeMargin_rad, kPi / 2);
      packets_.push_back({axis, std::cos(half_angle_rad), std::sin(half_angle_rad)});
    }
  }
  packet_begin_.push_back(static_cast<std::uint32_t>(packets_.size()));
  cache_ = std::make_unique<Cache>();

  const double az = config_.sun_azimuth_deg * kPi / 180.0;
  const double el = config_.sun_elevation_deg * kPi / 180.0;
  sun_W_ = Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el))
               .cast<float>();
  sun_up_ = config_.sun_elevation_deg > 0.0;

  encode_.resize(65536);
  for (std::size_t i = 0; i < encode_.size(); ++i)
    encode_[i] = static_cast<std::uint8_t>(
        std::lround(255.0 * std::pow(static_cast<double>(i) / 65535.0, 1.0 / config_.gamma)));
}

FisheyeStereo::~FisheyeStereo() = default;
FisheyeStereo::FisheyeStereo(FisheyeStereo&&) noexcept = default;

std::size_t FisheyeStereo::last_capture_rays() const { return cache_->last_capture_rays; }

std::vector<Ray> FisheyeStereo::WorldRays(Eye eye) const {
  const Eigen::Vector3f origin = X_WC(eye).translation().cast<float>();
  std::vector<Ray> rays(direction_W_.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    rays[i].origin_m = origin;
    rays[i].direction = direction_W_[i];
  }
  return rays;
}

double CameraExtinctionPerM(const core::WeatherConfig& weather) {
  return OpticalExtinctionPerM(weather, kVisibleWavelengthNm);
}

FisheyeStereo::Light FisheyeStereo::FrameLight(const core::WeatherConfig& weather) const {
  Light light;
  light.gain = weather.illumination * config_.exposure;
  light.beta_per_m = CameraExtinctionPerM(weather);
  light.airlight = light.gain * kSkyHorizon;
  return light;
}

std::vector<FisheyeStereo::Streak> FisheyeStereo::RainStreaks(double rain_mm_h,
                                                              core::RngStream rng) const {
  std::vector<Streak> streaks;
  if (rain_mm_h <= 0.0) return streaks;
  // Drops within a metre or so of the lens, blurred over the exposure: about
  // one streak per mm/h in a 640 x 480 frame, a few at drizzle and dozens in
  // a downpour.
  const int w = table_.width_px, h = table_.height_px;
  const double expected = rain_mm_h * (static_cast<double>(w) * h) / (640.0 * 480.0);
  const auto count = static_cast<std::size_t>(std::min(expected + rng.Uniform(), 5000.0));
  for (std::size_t k = 0; k < count; ++k) {
    Streak s;
    s.u0 = rng.Uniform(0.0, w);
    s.v0 = rng.Uniform(-0.1 * h, h);
    s.v1 = s.v0 + rng.Uniform(0.04, 0.12) * h;
    s.du_dv = std::tan(rng.Normal(0.1, 0.05));  // falling with a light wind
    s.alpha = rng.Uniform(0.15, 0.35);
    streaks.push_back(s);
  }
  return streaks;
}

std::vector<FisheyeStereo::PixelBox> FisheyeStereo::SubsampledBoxes(
    int eye, const std::vector<BoundingSphere>& spheres) const {
  std::vector<PixelBox> boxes;
  const Eigen::Isometry3d X_CW = X_WC_[eye].inverse();
  for (const BoundingSphere& sphere : spheres) {
    const Eigen::Vector3d c_C = X_CW * sphere.center_m;
    const double distance_m = c_C.norm();
    if (!(distance_m > sphere.radius_m) || sphere.radius_m <= 0.0) continue;
    // The sphere's image: the centre and 16 points of its silhouette cone.
    const Eigen::Vector3d axis = c_C / distance_m;
    const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
    const double sin_a = sphere.radius_m / distance_m, cos_a = std::sqrt(1.0 - sin_a * sin_a);
    Eigen::AlignedBox2d image;
    if (const auto px = model_.Project(axis)) image.extend(*px);
    for (int k = 0; k < 16; ++k) {
      const double phi = 2.0 * kPi * k / 16.0;
      const Eigen::Vector3d edge = cos_a * axis + sin_a * (std::cos(phi) * e1 + std::sin(phi) * e2);
      if (const auto px = model_.Project(edge)) image.extend(*px);
    }
    if (image.isEmpty()) continue;
    if (image.sizes().maxCoeff() > kMaxSubsampledSpanPx) continue;
    // One pixel of margin: the 16 points under-sample the silhouette's
    // curvature, and the pixel's own half-width reaches past its centre.
    PixelBox box;
    box.u0 = std::max(0, static_cast<int>(std::floor(image.min().x() - 1.0)));
    box.v0 = std::max(0, static_cast<int>(std::floor(image.min().y() - 1.0)));
    box.u1 = std::min(table_.width_px - 1, static_cast<int>(std::ceil(image.max().x() + 1.0)));
    box.v1 = std::min(table_.height_px - 1, static_cast<int>(std::ceil(image.max().y() + 1.0)));
    boxes.push_back(box);
  }
  return boxes;
}

float FisheyeStereo::SubsampledRadiance(int eye, int u, int v, const Light& light,
                                        std::vector<Ray>& rays, std::vector<RayHit>& hits) const {
  const Eigen::Matrix3d& R_WC = X_WC_[eye].linear();
  const Eigen::Vector3f origin = X_WC_[eye].translation().cast<float>();
  rays.clear();
  for (int j = 0; j < kSubsamples; ++j) {
    for (int i = 0; i < kSubsamples; ++i) {
      const Eigen::Vector3d d_C =
          model_.Unproject(u - 0.5 + (i + 0.5) / kSubsamples, v - 0.5 + (j + 0.5) / kSubsamples);
      if (d_C.isZero()) continue;
      Ray ray;
      ray.origin_m = origin;
      ray.direction = (R_WC * d_C).cast<float>();
      rays.push_back(ray);
    }
  }
  hits.resize(rays.size());
  scene_.IntersectMany(rays.data(), hits.data(), rays.size());
  double sum = 0.0;
  for (std::size_t k = 0; k < rays.size(); ++k) sum += Radiance(hits[k], rays[k].direction, light);
  return static_cast<float>(sum / static_cast<double>(std::max<std::size_t>(1, rays.size())));
}

float FisheyeStereo::Radiance(const RayHit& hit, const Eigen::Vector3f& direction_W,
                              const Light& light) const {
  if (!hit.hit()) {
    if (light.beta_per_m > 0.0) return static_cast<float>(light.airlight);
    return static_cast<float>(light.gain * SkyRadiance(direction_W.z()));
  }
  const double albedo = scene_.material(hit.material).albedo;
  const Eigen::Vector3f& n = hit.normal_w;
  const double sun = sun_up_ ? kSunRadiance * std::max(0.0f, n.dot(sun_W_)) : 0.0;
  const double sky = kSkyAmbient * (0.5 * (1.0 + n.z()) + kGroundAlbedo * 0.5 * (1.0 - n.z()));
  double L = light.gain * albedo * (sun + sky);
  if (light.beta_per_m > 0.0) {
    const double transmittance = std::exp(-light.beta_per_m * hit.t);
    L = L * transmittance + light.airlight * (1.0 - transmittance);
  }
  return static_cast<float>(L);
}

bool FisheyeStereo::PacketMeets(std::size_t packet, std::uint32_t first, std::uint32_t count,
                                const std::vector<ObjectCone>& objects) const {
  const PacketCone& cone = packets_[packet];
  for (const ObjectCone& object : objects) {
    // The cones can overlap only if their axes are at most the sum of the
    // half-angles apart (both are at most 90 degrees, so cos decreases over
    // the sum); then ask each ray.
    const double cos_reach = cone.cos_half * object.cos_half - cone.sin_half * object.sin_half;
    if (cone.axis.dot(object.axis) < cos_reach) continue;
    for (std::uint32_t i = first; i < first + count; ++i)
      if (direction_W_[i].cast<double>().normalized().dot(object.axis) >= object.cos_half)
        return true;
  }
  return false;
}

std::size_t FisheyeStereo::CenterRadiance(int eye, int v, const Light& light, const EyePlan& plan,
                                          std::vector<Ray>& rays, std::vector<RayHit>& hits,
                                          std::vector<float>& radiance) const {
  const std::uint32_t begin = row_begin_[v], end = row_begin_[v + 1];
  const Eigen::Vector3f origin = X_WC_[eye].translation().cast<float>();
  radiance.assign(table_.width_px, 0.0f);
  if (plan.full) {
    const std::size_t n = end - begin;
    rays.resize(n);
    hits.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      rays[i].origin_m = origin;
      rays[i].direction = direction_W_[begin + i];
    }
    // One row of a fisheye image is a coherent fan of rays: Embree's packets
    // traverse it faster than single rays.
    scene_.IntersectMany(rays.data(), hits.data(), n);
    for (std::size_t i = 0; i < n; ++i)
      radiance[column_[begin + i]] = Radiance(hits[i], direction_W_[begin + i], light);
    return n;
  }

  const std::vector<float>& cached = cache_->radiance[eye];
  for (std::uint32_t i = begin; i < end; ++i) radiance[column_[i]] = cached[i];
  // A packet with a ray that meets a moving object is cast as the full
  // render casts it, all 8 rays together: the other rays' hits may depend
  // on their packet (Embree switches between packet and single-ray
  // traversal by the number of active rays).
  std::size_t cast = 0;
  for (std::uint32_t p = packet_begin_[v]; p < packet_begin_[v + 1]; ++p) {
    const std::uint32_t first = begin + 8 * (p - packet_begin_[v]);
    const std::uint32_t count = std::min<std::uint32_t>(8, end - first);
    if (!PacketMeets(p, first, count, plan.objects)) continue;
    rays.resize(count);
    hits.resize(count);
    for (std::uint32_t k = 0; k < count; ++k) {
      rays[k].origin_m = origin;
      rays[k].direction = direction_W_[first + k];
    }
    scene_.IntersectMany(rays.data(), hits.data(), count);
    for (std::uint32_t k = 0; k < count; ++k)
      radiance[column_[first + k]] = Radiance(hits[k], direction_W_[first + k], light);
    cast += count;
  }
  return cast;
}

std::size_t FisheyeStereo::RenderRow(int eye, int v, const Light& light,
                                     const std::vector<Streak>& streaks,
                                     const std::vector<PixelBox>& boxes, const EyePlan& plan,
                                     std::uint64_t frame_key, std::vector<Ray>& rays,
                                     std::vector<RayHit>& hits, std::vector<float>& radiance,
                                     float* radiance_out, std::uint8_t* out) const {
  const int w = table_.width_px;
  std::size_t cast = CenterRadiance(eye, v, light, plan, rays, hits, radiance);

  const std::uint8_t* valid = &table_.valid[static_cast<std::size_t>(v) * w];
  // Overlapping boxes must not integrate a pixel twice: the first box
  // covering a column takes it.
  int done_until = -1;
  for (const PixelBox& box : boxes) {
    if (v < box.v0 || v > box.v1) continue;
    for (int u = std::max(box.u0, done_until + 1); u <= box.u1; ++u)
      if (valid[u]) {
        radiance[u] = SubsampledRadiance(eye, u, v, light, rays, hits);
        cast += rays.size();
      }
    done_until = std::max(done_until, box.u1);
  }
  if (radiance_out) std::copy(radiance.begin(), radiance.end(), radiance_out);
  if (!out) return cast;

  const float streak_radiance = static_cast<float>(kStreakBrightness * light.airlight);
  for (const Streak& s : streaks) {
    if (v < s.v0 || v > s.v1) continue;
    const long u = std::lround(s.u0 + (v - s.v0) * s.du_dv);
    if (u < 0 || u >= w || !valid[u]) continue;
    radiance[u] += static_cast<float>(s.alpha) * (streak_radiance - radiance[u]);
  }

  // The noise of each row is the counter-based stream of (frame, eye, row),
  // one standard normal per column, so threads may render rows in any order.
  thread_local std::vector<float> noise;
  noise.assign(w, 0.0f);
  if (config_.sensor_noise)
    core::CounterNormal(
        core::Mix64(frame_key ^ core::Mix64((static_cast<std::uint64_t>(eye) << 32) | v)))
        .Fill(0, noise.data(), noise.size());
  // Electrons, shot and read noise, the grey level's 16-bit code: a
  // branch-free pass the compiler vectorises (invalid pixels count as
  // black here and are written 0 below), then the encoding table.
  const double full_well = config_.full_well_e;
  const double read_variance = config_.read_noise_e * config_.read_noise_e;
  const double noise_on = config_.sensor_noise ? 1.0 : 0.0;
  thread_local std::vector<std::int32_t> code;
  code.resize(w);
  const float* __restrict r = radiance.data();
  const float* __restrict n = noise.data();
  std::int32_t* __restrict c = code.data();
  for (int u = 0; u < w; ++u) {
    float radiance_u = r[u];
    radiance_u = valid[u] ? radiance_u : 0.0f;
    double electrons = static_cast<double>(radiance_u) * full_well;
    electrons += std::sqrt(std::max(electrons, 0.0) + read_variance) * (noise_on * n[u]);
    const double x = std::min(std::max(electrons / full_well, 0.0), 1.0);
    c[u] = static_cast<std::int32_t>(x * 65535.0 + 0.5);
  }
  for (int u = 0; u < w; ++u) out[u] = valid[u] ? encode_[static_cast<std::size_t>(c[u])] : 0;
  return cast;
}

template <typename RowRangeFunction>
void FisheyeStereo::ForEachRow(int rows, RowRangeFunction&& body) const {
  const tbb::blocked_range<int> all_rows(0, rows, 2);
  if (max_threads_ > 0) {
    tbb::task_arena arena(max_threads_);
    arena.execute([&] { tbb::parallel_for(all_rows, body); });
  } else {
    tbb::parallel_for(all_rows, body);
  }
}

std::size_t FisheyeStereo::BuildCache(const Light& light) const {
  Cache& cache = *cache_;
  cache.built = true;
  cache.light = light;
  const Eigen::AlignedBox3d bounds = scene_.static_bounds();
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(kStaticBoundsMargin_m);
  for (int eye = 0; eye < 2; ++eye) {
    const Eigen::Vector3d o = X_WC_[eye].translation().cast<float>().cast<double>();
    cache.usable[eye] = !bounds.isEmpty() && (o.array() > (bounds.min() + margin).array()).all() &&
                        (o.array() < (bounds.max() - margin).array()).all();
    cache.radiance[eye].assign(cache.usable[eye] ? direction_W_.size() : 0, 0.0f);
  }
  const int h = table_.height_px;
  std::atomic<std::size_t> cast{0};
  ForEachRow(2 * h, [&](const tbb::blocked_range<int>& rows) {
    std::vector<Ray> rays;
    std::vector<RayHit> hits;
    std::size_t n_cast = 0;
    for (int r = rows.begin(); r != rows.end(); ++r) {
      const int eye = r / h, v = r % h;
      if (!cache.usable[eye]) continue;
      const std::uint32_t begin = row_begin_[v], end = row_begin_[v + 1];
      const std::size_t n = end - begin;
      const Eigen::Vector3f origin = X_WC_[eye].translation().cast<float>();
      rays.resize(n);
      hits.resize(n);
      for (std::size_t i = 0; i < n; ++i) {
        rays[i].origin_m = origin;
        rays[i].direction = direction_W_[begin + i];
      }
      scene_.IntersectManyStatic(rays.data(), hits.data(), n);
      for (std::size_t i = 0; i < n; ++i)
        cache.radiance[eye][begin + i] = Radiance(hits[i], direction_W_[begin + i], light);
      n_cast += n;
    }
    cast += n_cast;
  });
  return cast;
}

std::vector<FisheyeStereo::EyePlan> FisheyeStereo::PlanEyes() const {
  std::vector<EyePlan> plans(2);
  if (!static_cache_) return plans;
  for (int eye = 0; eye < 2; ++eye) {
    if (!cache_->usable[eye]) continue;
    EyePlan& plan = plans[eye];
    plan.full = false;
    const Eigen::Vector3d o = X_WC_[eye].translation().cast<float>().cast<double>();
    for (const BoundingSphere& sphere : scene_.moving_object_bounds()) {
      const double radius_m = sphere.radius_m * (1.0 + kSphereMarginRel) + kSphereMargin_m;
      const Eigen::Vector3d to_center = sphere.center_m - o;
      const double distance_m = to_center.norm();
      if (!(distance_m > radius_m)) {  // the eye is inside (or the pose is not finite)
        plan.full = true;
        plan.objects.clear();
        break;
      }
      const double sin_half = radius_m / distance_m;
      plan.objects.push_back(
          {to_center / distance_m, std::sqrt(1.0 - sin_half * sin_half), sin_half});
    }
  }
  return plans;
}

StereoFrame FisheyeStereo::Capture(double t_s, const core::WeatherConfig& weather,
                                   core::RngStream& noise) const {
  StereoFrame frame;
  Render(t_s, weather, noise.NextU64(), &frame, nullptr);
  return frame;
}

std::vector<float> FisheyeStereo::CaptureRadiance(double t_s,
                                                  const core::WeatherConfig& weather) const {
  std::vector<float> radiance;
  Render(t_s, weather, 0, nullptr, &radiance);
  return radiance;
}

void FisheyeStereo::Render(double t_s, const core::WeatherConfig& weather, std::uint64_t frame_key,
                           StereoFrame* frame, std::vector<float>* radiance_out) const {
  const core::RngStream frame_rng(frame_key);
  const Light light = FrameLight(weather);
  std::vector<Streak> streaks[2];
  if (frame) {
    streaks[0] = RainStreaks(weather.rain_mm_h, frame_rng.Derive("rain/left"));
    streaks[1] = RainStreaks(weather.rain_mm_h, frame_rng.Derive("rain/right"));
  }
  const std::vector<BoundingSphere> spheres =
      small_objects_ ? small_objects_(t_s) : std::vector<BoundingSphere>{};
  std::vector<PixelBox> boxes[2] = {SubsampledBoxes(0, spheres), SubsampledBoxes(1, spheres)};
  // Sorted by first column, so RenderRow can skip columns already done.
  for (auto& b : boxes)
    std::sort(b.begin(), b.end(), [](const PixelBox& a, const PixelBox& c) { return a.u0 < c.u0; });

  std::size_t cast = 0;
  if (static_cache_ && (!cache_->built || !cache_->light.Same(light))) cast += BuildCache(light);
  const std::vector<EyePlan> plans = PlanEyes();

  const int w = table_.width_px, h = table_.height_px;
  const std::size_t image_size = static_cast<std::size_t>(w) * h;
  GrayImage* images[2] = {nullptr, nullptr};
  if (frame) {
    frame->t_capture_s = t_s;
    images[0] = &frame->left;
    images[1] = &frame->right;
    for (GrayImage* image : images) {
      image->width = w;
      image->height = h;
      image->pixels.assign(image_size, 0);
    }
  }
  if (radiance_out) radiance_out->assign(2 * image_size, 0.0f);

  std::atomic<std::size_t> rows_cast{0};
  ForEachRow(2 * h, [&](const tbb::blocked_range<int>& rows) {
    std::vector<Ray> rays;
    std::vector<RayHit> hits;
    std::vector<float> radiance;
    std::size_t n_cast = 0;
    for (int r = rows.begin(); r != rows.end(); ++r) {
      const int eye = r / h, v = r % h;
      const std::size_t row_offset = static_cast<std::size_t>(v) * w;
      n_cast += RenderRow(
          eye, v, light, streaks[eye], boxes[eye], plans[eye], frame_key, rays, hits, radiance,
          radiance_out ? radiance_out->data() + eye * image_size + row_offset : nullptr,
          frame ? images[eye]->pixels.data() + row_offset : nullptr);
    }
    rows_cast += n_cast;
  });
  cache_->last_capture_rays = cast + rows_cast;
}

}  // namespace uavsim::sensors
