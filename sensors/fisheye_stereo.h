// The stereo fisheye camera: two global-shutter eyes with the same Mei
// intrinsics (fisheye_model.h), one Embree ray per pixel through the exact
// inverse of the model, shaded into 8-bit grey images.
//
// Frames: the config's pose is the rig's body frame B (REP 103, x forward);
// each eye's optical frame C has x_C = -y_B, y_C = -z_B, z_C = x_B. The left
// eye sits at the pose, the right eye baseline_m along +x_C (to the right).
// Pixel (u, v) of an image sees along the ray of ray_table() at (u, v).
//
// Image formation (linear radiance, full scale = 1 at exposure 1):
//   hit:  L = gain * albedo * (0.9 max(0, n.s) + 0.45 ((1 + n_z)/2 + 0.15 (1 - n_z)/2))
//         (Lambertian sun of direction s from the config, sky ambient over
//         the upper hemisphere, ground bounce of albedo 0.15 over the lower;
//         n the world normal facing the camera, albedo the material's)
//   miss: L = gain * sky(z), sky(z) = 0.35 + 0.4 (1 - z)^2 for the ray's
//         world z component (0.75 at the horizon, 0.35 at the zenith)
//   gain = weather.illumination * exposure (night, 0.01, is dark and noisy)
//   fog/rain: beta = CameraExtinctionPerM(weather) = 3.912 / visibility_m
//         (Koschmieder) + beta_rain(rain_mm_h), the shared optical atmosphere
//         of sensors/atmosphere.h at 550 nm (rain: Marshall-Palmer drops, the
//         same law and value as the LiDAR's),
//         L <- L e^(-beta d) + A (1 - e^(-beta d)), A = gain * sky(horizon),
//         d the hit distance in metres; misses become A (d = infinity)
//   rain: a few streaks a frame (about rain_mm_h per eye at 640 x 480)
//   sensor: N = L * full_well_e electrons, N + sqrt(N + read_noise_e^2) * z
//         (shot noise with variance N, Gaussian read noise), clipped to full
//         well, then 255 * (N / full_well_e)^(1/gamma), rounded
// Pixels outside the lens's valid domain are 0.
//
// Small objects: one ray per pixel centre would let a UAV 70 m away (under
// two pixels across) slip between the samples or flicker from frame to
// frame. A real pixel integrates over its area, so the pixels around the
// image of each sphere that set_small_objects reports are integrated with
// kSubsamples x kSubsamples stratified rays (objects whose image spans more
// than kMaxSubsampledSpanPx pixels are resolved by the pixel centres alone).
//
// Static-scene cache (set_static_cache, on by default): the cameras and the
// static world never move, so each eye keeps the radiance of every valid
// pixel's centre ray cast against the static world alone
// (RaycastScene::IntersectManyStatic), built at the first Capture and
// rebuilt whenever the frame's light (illumination, exposure, fog and rain
// extinction) differs in any bit. Each frame re-casts against the full scene
// only the packets of 8 pixels of a row (the packets the full render casts)
// with a ray that meets a sphere enclosing a moving object as the scene is
// posed (RaycastScene::moving_object_bounds, the meshes' own extent widened
// by 1 % + 1 cm; set_small_objects plays no part). The sub-pixel
// integration, rain streaks and noise are per frame as before.
// Exactness: the images (and CaptureRadiance) are bit-identical to the full
// render's (the cache off). The moving objects cast no shadows, so only the
// rays that meet them see them; a packet none of whose rays meets one gets
// the same hits from the static-only top level as from the full one (see
// IntersectManyStatic). A whole packet is re-cast because a ray's hit may
// depend on the other rays of its packet. An eye whose centre is not inside
// the static world's bounds (where that argument does not hold), or lies
// inside a moving object's sphere, casts every pixel that frame.
//
// Determinism: Capture draws exactly one 64-bit value from `noise`; every
// pixel's z is the counter-based normal (core/counter_normal.h) of the
// key (that value, eye, row) at its column, so the images are the same
// whatever the number of threads.
// Threads: Capture runs tbb::parallel_for over rows; it may run concurrently
// with other const calls on the same scene (the scene must not be posed
// meanwhile), but not with another Capture of the same camera. The scene
// must outlive the camera.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "core/rng.h"
#include "core/weather.h"
#include "sensors/fisheye_model.h"
#include "sensors/fisheye_stereo_config.h"
#include "sensors/frames.h"
#include "sensors/raycast_scene.h"

namespace uavsim::sensors {

// The camera's extinction coefficient of fog and rain together, 1/m: the
// optical atmosphere (sensors/atmosphere.h) at kVisibleWavelengthNm, so
// exactly 3.912 / visibility_m in fog alone, and in rain the LiDAR's value.
// The beta of the image formation above.
double CameraExtinctionPerM(const core::WeatherConfig& weather);

class FisheyeStereo {
 public:
  enum class Eye { kLeft = 0, kRight = 1 };
  // The moving objects' bounding spheres at time t_s (e.g. each UAV's
  // position and half its size_m diagonal).
  using SmallObjectsFunction = std::function<std::vector<BoundingSphere>(double t_s)>;

  static constexpr int kSubsamples = 4;
  static constexpr int kMaxSubsampledSpanPx = 24;

  // Computes the per-pixel ray table once.
  FisheyeStereo(const FisheyeStereoConfig& config, const RaycastScene& scene);
  ~FisheyeStereo();
  FisheyeStereo(FisheyeStereo&&) noexcept;
  FisheyeStereo& operator=(FisheyeStereo&&) = delete;  // holds a reference to the scene

  // Renders both eyes of the scene as it is posed now (the caller has called
  // scene.SetTime(t_s)); t_s is stamped on the frame.
  StereoFrame Capture(double t_s, const core::WeatherConfig& weather, core::RngStream& noise) const;

  // Both eyes' linear radiance (left, then right; row-major, 0 outside the
  // lens) as Capture computes it before rain streaks and sensor noise: the
  // same rays, cache and sub-pixel integration. Draws no randomness; for
  // comparing renders more finely than 8 bits.
  std::vector<float> CaptureRadiance(double t_s, const core::WeatherConfig& weather) const;

  // Objects whose pixels Capture integrates over their area (see above);
  // called once per Capture with its t_s. Unset: pixel centres only.
  void set_small_objects(SmallObjectsFunction small_objects) {
    small_objects_ = std::move(small_objects);
  }

  // The static-scene cache (see above): on by default; off renders every
  // pixel every frame. Either way the images are the same.
  void set_static_cache(bool on) { static_cache_ = on; }
  bool static_cache() const { return static_cache_; }

  // At most `max_threads` threads for Capture (0: TBB's default, all cores).
  // Does not change the images.
  void set_max_threads(int max_threads) { max_threads_ = max_threads; }
  int max_threads() const { return max_threads_; }

  const FisheyeStereoConfig& config() const { return config_; }
  const FisheyeModel& model() const { return model_; }
  const RayTable& ray_table() const { return table_; }  // both eyes share the intrinsics
  // Pose of an eye's optical frame in the world.
  const Eigen::Isometry3d& X_WC(Eye eye) const { return X_WC_[static_cast<int>(eye)]; }
  // The world-frame rays Capture casts for one eye (valid pixels, row-major),
  // for benchmarks that time the same rays through other APIs.
  std::vector<Ray> WorldRays(Eye eye) const;
  // Rays cast per Capture without the cache: the valid pixels of both eyes.
  std::size_t rays_per_frame() const { return 2 * table_.valid_count; }
  // Rays the last Capture cast, all included: pixel centres (against the
  // full scene, or the static world when it built the cache) and sub-pixel
  // rays. 0 before the first Capture.
  std::size_t last_capture_rays() const;

 private:
  struct Light;
  struct Streak;
  struct PixelBox {
    int u0, v0, u1, v1;  // inclusive
  };
  // The cone (world frame) holding the directions of one packet of 8 pixel
  // centres of a row, as RaycastScene::IntersectMany groups them.
  struct PacketCone {
    Eigen::Vector3d axis;
    double cos_half, sin_half;  // of the half-angle, at most 90 degrees
  };
  // A moving object's sphere as an eye sees it: the cone of directions that
  // meet it.
  struct ObjectCone {
    Eigen::Vector3d axis;
    double cos_half, sin_half;
  };
  // How an eye casts its pixel centres this frame.
  struct EyePlan {
    bool full = true;                 // every pixel against the full scene
    std::vector<ObjectCone> objects;  // else: the cache, re-casting packets that meet these
  };
  struct Cache;

  Light FrameLight(const core::WeatherConfig& weather) const;
  std::vector<Streak> RainStreaks(double rain_mm_h, core::RngStream rng) const;
  std::vector<PixelBox> SubsampledBoxes(int eye, const std::vector<BoundingSphere>& spheres) const;
  float SubsampledRadiance(int eye, int u, int v, const Light& light, std::vector<Ray>& rays,
                           std::vector<RayHit>& hits) const;
  float Radiance(const RayHit& hit, const Eigen::Vector3f& direction_W, const Light& light) const;
  template <typename RowFunction>
  void ForEachRow(int rows, RowFunction&& row) const;
  std::size_t BuildCache(const Light& light) const;
  std::vector<EyePlan> PlanEyes() const;
  bool PacketMeets(std::size_t packet, std::uint32_t first, std::uint32_t count,
                   const std::vector<ObjectCone>& objects) const;
  std::size_t CenterRadiance(int eye, int v, const Light& light, const EyePlan& plan,
                             std::vector<Ray>& rays, std::vector<RayHit>& hits,
                             std::vector<float>& radiance) const;
  // Renders into `frame` (streaks and noise from frame_key) and/or
  // `radiance` (2 w h floats).
  void Render(double t_s, const core::WeatherConfig& weather, std::uint64_t frame_key,
              StereoFrame* frame, std::vector<float>* radiance) const;
  std::size_t RenderRow(int eye, int v, const Light& light, const std::vector<Streak>& streaks,
                        const std::vector<PixelBox>& boxes, const EyePlan& plan,
                        std::uint64_t frame_key, std::vector<Ray>& rays, std::vector<RayHit>& hits,
                        std::vector<float>& radiance, float* radiance_out, std::uint8_t* out) const;

  FisheyeStereoConfig config_;
  const RaycastScene& scene_;
  FisheyeModel model_;
  RayTable table_;
  Eigen::Isometry3d X_WC_[2];
  // The valid pixels' directions in the world frame, row by row: row v holds
  // entries row_begin_[v] .. row_begin_[v + 1] - 1, at columns column_[i].
  std::vector<Eigen::Vector3f> direction_W_;
  std::vector<std::uint32_t> row_begin_;
  std::vector<std::uint16_t> column_;
  std::vector<PacketCone>
      packets_;  // row v's packets: packet_begin_[v] .. packet_begin_[v + 1] - 1
  std::vector<std::uint32_t> packet_begin_;
  Eigen::Vector3f sun_W_;
  bool sun_up_;
  std::vector<std::uint8_t> encode_;  // linear [0, 1] in 65536 steps -> gamma-encoded 8 bits
  SmallObjectsFunction small_objects_;
  int max_threads_ = 0;
  bool static_cache_ = true;
  std::unique_ptr<Cache> cache_;  // filled by Capture
};

}  // namespace uavsim::sensors
