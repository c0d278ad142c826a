#include "sim/mcap_recorder.h"

#include <openssl/evp.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cmath>
#include <cstring>

#include "core/physical_constants.h"
#include "core/time.h"
#include "sim/foxglove_schemas.h"
#include "sim/version.h"

namespace uavsim::sim {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "PointCloud data is little-endian float32: copied from memory as it is");

using core::Json;

std::uint64_t Ns(core::SimTime t) {
  return static_cast<std::uint64_t>(std::max<core::SimTime>(0, t));
}
std::uint64_t Ns(double t_s) { return Ns(core::Seconds(t_s)); }

Json Time(std::uint64_t ns) { return {{"sec", ns / 1000000000ull}, {"nsec", ns % 1000000000ull}}; }
Json Vec3(const Eigen::Vector3d& v) { return {{"x", v.x()}, {"y", v.y()}, {"z", v.z()}}; }
// To the millimetre: the world's vertices print short.
Json Vec3Mm(const Eigen::Vector3f& v) {
  const auto mm = [](float x) { return std::round(static_cast<double>(x) * 1000.0) / 1000.0; };
  return {{"x", mm(v.x())}, {"y", mm(v.y())}, {"z", mm(v.z())}};
}
Json Quat(const Eigen::Quaterniond& q) {
  return {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}};
}
Json Pose(const Eigen::Isometry3d& X) {
  return {{"position", Vec3(X.translation())},
          {"orientation", Quat(Eigen::Quaterniond(X.linear()))}};
}
Json Position(const Eigen::Vector3d& p) { return Pose(Eigen::Isometry3d(Eigen::Translation3d(p))); }
Json Color(double r, double g, double b, double a = 1.0) {
  return {{"r", r}, {"g", g}, {"b", b}, {"a", a}};
}

std::string Base64(const void* data, std::size_t n) {
  std::string out(4 * ((n + 2) / 3) + 1, '\0');
  const int written = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()),
                                      static_cast<const unsigned char*>(data), static_cast<int>(n));
  out.resize(static_cast<std::size_t>(written));
  return out;
}

// A SceneEntity in the world frame with no primitives (lifetime 0: until
// replaced by an entity of the same id).
Json Entity(const std::string& id, std::uint64_t ns) {
  Json e = {{"timestamp", Time(ns)}, {"frame_id", "world"},   {"id", id},
            {"lifetime", Time(0)},   {"frame_locked", false}, {"metadata", Json::array()}};
  for (const char* kind :
       {"arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"})
    e[kind] = Json::array();
  return e;
}
Json Label(const Eigen::Vector3d& at, const std::string& text) {
  return {{"pose", Position(at)},    {"billboard", true},       {"font_size", 14.0},
          {"scale_invariant", true}, {"color", Color(1, 1, 1)}, {"text", text}};
}
Json Solid(const Eigen::Isometry3d& X, const Eigen::Vector3d& size_m, const Json& color) {
  return {{"pose", Pose(X)}, {"size", Vec3(size_m)}, {"color", color}};
}
Json SceneUpdate(Json entities) {
  return {{"deletions", Json::array()}, {"entities", std::move(entities)}};
}

// By core::BuiltinMaterial: ground, concrete, glass, metal, foliage, drone, bird.
Json MaterialColor(std::uint32_t material) {
  static const double rgb[][3] = {{0.35, 0.35, 0.37}, {0.75, 0.73, 0.70}, {0.55, 0.70, 0.85},
                                  {0.45, 0.45, 0.50}, {0.25, 0.55, 0.25}, {0.10, 0.10, 0.10},
                                  {0.60, 0.45, 0.30}};
  if (material >= sizeof rgb / sizeof rgb[0]) return Color(0.7, 0.7, 0.7);
  return Color(rgb[material][0], rgb[material][1], rgb[material][2]);
}

Json Transform(std::uint64_t ns, const std::string& child, const Eigen::Isometry3d& X_WC) {
  return {{"timestamp", Time(ns)},
          {"parent_frame_id", "world"},
          {"child_frame_id", child},
          {"translation", Vec3(X_WC.translation())},
          {"rotation", Quat(Eigen::Quaterniond(X_WC.linear()))}};
}

// A camera eye's optical frame in the rig's body frame: x_C = -y_B,
// y_C = -z_B, z_C = x_B (sensors/fisheye_stereo.h); the right eye
// baseline_m along x_C.
Eigen::Isometry3d X_WEye(const sensors::FisheyeStereoConfig& c, bool right) {
  Eigen::Isometry3d X = c.pose.ToIsometry();
  X.linear() = X.linear() * sensors::R_BC();
  return right ? X * Eigen::Translation3d(c.baseline_m, 0.0, 0.0) : X;
}

// Kannala-Brandt coefficients k1..k4 (theta_d = theta (1 + k1 theta^2 + ...
// + k4 theta^8)) fitted by least squares to the Mei model's radial mapping
// (fisheye_model.h without p1, p2: m = rho (1 + k1 rho^2 + k2 rho^4 + k3
// rho^6), rho = sin theta / (cos theta + xi)) from the axis out to the
// image's farthest corner, where the mapping stops growing if sooner.
// Returns the four coefficients and the largest error in pixels.
std::pair<Eigen::Vector4d, double> FitKannalaBrandt(const sensors::FisheyeStereoConfig& c) {
  const auto mei = [&c](double theta) {
    const double rho = std::sin(theta) / (std::cos(theta) + c.xi), r2 = rho * rho;
    return rho * (1.0 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3)));
  };
  const double du = std::max(c.cx_px, c.width_px - c.cx_px) / c.fx_px;
  const double dv = std::max(c.cy_px, c.height_px - c.cy_px) / c.fy_px;
  const double corner = std::hypot(du, dv);
  constexpr int kSamples = 400;
  double theta_max = 0.0;
  for (double t = 1e-3; t < core::kPi - 1e-3; t += 1e-3) {
    if (std::cos(t) + c.xi <= 0.0 || mei(t) <= mei(theta_max)) break;
    theta_max = t;
    if (mei(t) >= corner) break;
  }
  Eigen::MatrixXd A(kSamples, 4);
  Eigen::VectorXd b(kSamples);
  for (int i = 0; i < kSamples; ++i) {
    const double t = theta_max * (i + 1) / kSamples;
    for (int j = 0; j < 4; ++j) A(i, j) = std::pow(t, 3 + 2 * j);
    b(i) = mei(t) - t;
  }
  const Eigen::Vector4d k = A.colPivHouseholderQr().solve(b);
  const double worst = (A * k - b).cwiseAbs().maxCoeff() * std::max(c.fx_px, c.fy_px);
  return {k, worst};
}

std::vector<std::uint8_t> FloatsLe(const float* values, std::size_t count) {
  std::vector<std::uint8_t> bytes(count * sizeof(float));
  if (count) std::memcpy(bytes.data(), values, bytes.size());
  return bytes;
}

// A foxglove.PointCloud in the world frame of float32 fields.
Json Cloud(std::uint64_t ns, const std::vector<std::string>& fields,
           const std::vector<float>& values) {
  Json f = Json::array();
  for (std::size_t i = 0; i < fields.size(); ++i)
    f.push_back({{"name", fields[i]}, {"offset", 4 * i}, {"type", 7}});  // 7: FLOAT32
  const std::vector<std::uint8_t> bytes = FloatsLe(values.data(), values.size());
  return {{"timestamp", Time(ns)},
          {"frame_id", "world"},
          {"pose", Pose(Eigen::Isometry3d::Identity())},
          {"point_stride", 4 * fields.size()},
          {"fields", f},
          {"data", Base64(bytes.data(), bytes.size())}};
}

Json Image(std::uint64_t ns, const std::string& frame, const std::vector<std::uint8_t>& png) {
  return {{"timestamp", Time(ns)},
          {"frame_id", frame},
          {"data", Base64(png.data(), png.size())},
          {"format", "png"}};
}

// Per method, a colour of its own (Okabe-Ito), in the methods' order.
Json MethodColor(std::size_t i) {
  static const double rgb[][3] = {{0.90, 0.62, 0.00}, {0.34, 0.71, 0.91}, {0.80, 0.47, 0.65},
                                  {0.00, 0.45, 0.70}, {0.84, 0.37, 0.00}, {0.94, 0.89, 0.26}};
  const auto& c = rgb[i % (sizeof rgb / sizeof rgb[0])];
  return Color(c[0], c[1], c[2], 0.9);
}

}  // namespace

McapRecorder::McapRecorder(const std::string& path, const Scenario& scenario,
                           const WorldModel& world)
    : scenario_(scenario),
      writer_(path, results::McapOptions{"", std::string("uavsim ") + Version(),
                                         results::McapCompression::kZstd}) {
  WriteStatic(world);
}

std::uint16_t McapRecorder::Channel(const std::string& topic, const std::string& schema,
                                    const std::map<std::string, std::string>& metadata) {
  if (auto it = channels_.find(topic); it != channels_.end()) return it->second;
  auto s = schemas_.find(schema);
  if (s == schemas_.end())
    s = schemas_
            .emplace(schema, writer_.AddSchema(schema, "jsonschema", FoxgloveSchema(schema).dump()))
            .first;
  return channels_[topic] = writer_.AddChannel(s->second, topic, "json", metadata);
}

void McapRecorder::Write(const std::string& topic, const std::string& schema,
                         std::uint64_t log_time_ns, const core::Json& message,
                         const std::map<std::string, std::string>& metadata) {
  writer_.Write(Channel(topic, schema, metadata), log_time_ns, message.dump());
}

// t = 0: the world as triangles, the nodes and the base station, their frames.
void McapRecorder::WriteStatic(const WorldModel& world) {
  Json entities = Json::array();
  const auto& meshes = world.geometry().meshes;
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    Json points = Json::array(), indices = Json::array();
    for (const Eigen::Vector3f& v : meshes[i].vertices_m) points.push_back(Vec3Mm(v));
    for (const auto& t : meshes[i].triangles)
      for (std::uint32_t k : t) indices.push_back(k);
    Json e = Entity("world/" + std::to_string(i) + "/" + meshes[i].name, 0);
    e["triangles"].push_back({{"pose", Pose(Eigen::Isometry3d::Identity())},
                              {"points", std::move(points)},
                              {"color", MaterialColor(meshes[i].material)},
                              {"colors", Json::array()},
                              {"indices", std::move(indices)}});
    entities.push_back(std::move(e));
  }
  for (const NodeConfig& n : scenario_.nodes) {
    const Eigen::Isometry3d X_WB = n.sensor.pose().ToIsometry();
    Json e = Entity("node/" + n.id, 0);
    e["cubes"].push_back(Solid(X_WB, Eigen::Vector3d(0.6, 0.4, 0.3), Color(1.0, 0.3, 0.3)));
    e["texts"].push_back(Label(X_WB.translation() + Eigen::Vector3d(0, 0, 1.0), n.id));
    entities.push_back(std::move(e));
    Write("/tf/" + n.id, "foxglove.FrameTransform", 0, Transform(0, n.id, X_WB));
    if (n.sensor.type != sensors::SensorType::kFisheyeStereo) continue;
    for (const bool right : {false, true}) {
      const std::string eye = n.id + (right ? "/right" : "/left");
      Write("/tf/" + eye, "foxglove.FrameTransform", 0,
            Transform(0, eye, X_WEye(n.sensor.fisheye, right)));
    }
    WriteCalibrations(n);
  }
  const Eigen::Vector3d bs = scenario_.base_station.position_m;
  Json e = Entity("base_station", 0);
  e["cylinders"].push_back({{"pose", Position(bs - Eigen::Vector3d(0, 0, 0.5 * bs.z()))},
                            {"size", Vec3(Eigen::Vector3d(0.8, 0.8, bs.z()))},
                            {"bottom_scale", 1.0},
                            {"top_scale", 0.5},
                            {"color", Color(0.9, 0.9, 0.2)}});
  e["texts"].push_back(Label(bs + Eigen::Vector3d(0, 0, 2.0), "base station"));
  entities.push_back(std::move(e));
  Write("/tf/base_station", "foxglove.FrameTransform", 0,
        Transform(0, "base_station", Eigen::Isometry3d(Eigen::Translation3d(bs))));
  Write("/world", "foxglove.SceneUpdate", 0, SceneUpdate(std::move(entities)));
}

void McapRecorder::WriteCalibrations(const NodeConfig& n) {
  const sensors::FisheyeStereoConfig& c = n.sensor.fisheye;
  const auto [k, worst_px] = FitKannalaBrandt(c);
  char fit[160];
  std::snprintf(fit, sizeof fit,
                "kannala_brandt fitted to Mei (xi %.4g, k1 %.4g, k2 %.4g, k3 %.4g; p1, p2 left "
                "out): largest error %.3g px",
                c.xi, c.k1, c.k2, c.k3, worst_px);
  for (const bool right : {false, true}) {
    const std::string eye = n.id + (right ? "/right" : "/left");
    const double tx = right ? -c.fx_px * c.baseline_m : 0.0;  // ROS: P's Tx = -fx B
    const Json calibration = {
        {"timestamp", Time(0)},
        {"frame_id", eye},
        {"width", c.width_px},
        {"height", c.height_px},
        {"distortion_model", "kannala_brandt"},
        {"D", {k(0), k(1), k(2), k(3)}},
        {"K", {c.fx_px, 0.0, c.cx_px, 0.0, c.fy_px, c.cy_px, 0.0, 0.0, 1.0}},
        {"R", {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}},
        {"P", {c.fx_px, 0.0, c.cx_px, tx, 0.0, c.fy_px, c.cy_px, 0.0, 0.0, 0.0, 1.0, 0.0}}};
    Write("/" + eye + "/calibration", "foxglove.CameraCalibration", 0, calibration,
          {{"node", n.id}, {"modality", "camera"}, {"distortion_fit", fit}});
  }
}

void McapRecorder::RecordCamera(const std::string& node_id, const sensors::StereoFrame& frame,
                                const std::vector<std::uint8_t>& left_png,
                                const std::vector<std::uint8_t>& right_png) {
  const std::uint64_t ns = Ns(frame.t_capture_s);
  const std::map<std::string, std::string> meta{{"node", node_id}, {"modality", "camera"}};
  Write("/" + node_id + "/left/image", "foxglove.CompressedImage", ns,
        Image(ns, node_id + "/left", left_png), meta);
  Write("/" + node_id + "/right/image", "foxglove.CompressedImage", ns,
        Image(ns, node_id + "/right", right_png), meta);
}

void McapRecorder::RecordLidar(const std::string& node_id, const sensors::PointCloudFrame& frame) {
  static_assert(sizeof(sensors::LidarPoint) == 5 * sizeof(float), "LidarPoint is 5 floats");
  const std::uint64_t ns = Ns(frame.t_start_s);
  std::vector<float> values(5 * frame.points.size());
  if (!values.empty())
    std::memcpy(values.data(), frame.points.data(), values.size() * sizeof(float));
  Write("/" + node_id + "/points", "foxglove.PointCloud", ns,
        Cloud(ns, {"x", "y", "z", "intensity", "t_offset_s"}, values),
        {{"node", node_id}, {"modality", "lidar"}});
}

void McapRecorder::RecordRadar(const std::string& node_id, const sensors::RadarFrame& frame,
                               const std::vector<std::uint8_t>& range_doppler_png) {
  static_assert(sizeof(sensors::RadarPoint) == 5 * sizeof(float), "RadarPoint is 5 floats");
  const std::uint64_t ns = Ns(frame.t_capture_s);
  std::vector<float> values(5 * frame.points.size());
  if (!values.empty())
    std::memcpy(values.data(), frame.points.data(), values.size() * sizeof(float));
  const std::map<std::string, std::string> meta{{"node", node_id}, {"modality", "radar"}};
  Write("/" + node_id + "/points", "foxglove.PointCloud", ns,
        Cloud(ns, {"x", "y", "z", "radial_velocity_mps", "snr_db"}, values), meta);
  Write("/" + node_id + "/range_doppler", "foxglove.CompressedImage", ns,
        Image(ns, node_id, range_doppler_png), meta);
}

void McapRecorder::RecordWindow(double t_s, const WorldModel& world,
                                const std::map<std::string, Eigen::Vector3d>& estimates) {
  const std::uint64_t ns = Ns(t_s);
  Json truth = Json::array();
  for (std::size_t i = 0; i < world.uav_count(); ++i) {
    const std::string id = "uav/" + scenario_.uavs[i].id;
    const Eigen::Isometry3d X_WU = MultirotorPose(world.uav(i).StateAt(t_s));
    Json e = Entity(id, ns);
    e["cubes"].push_back(Solid(X_WU, scenario_.uavs[i].size_m, Color(0.1, 0.9, 0.2)));
    // A halo 3 m across, so that a 0.5 m drone is seen from the street.
    e["spheres"].push_back(Solid(X_WU, Eigen::Vector3d::Constant(3.0), Color(0.1, 0.9, 0.2, 0.25)));
    truth.push_back(std::move(e));
    Write("/tf/" + id, "foxglove.FrameTransform", ns, Transform(ns, id, X_WU));
  }
  Write("/truth", "foxglove.SceneUpdate", ns, SceneUpdate(std::move(truth)));
  const Eigen::Vector3d target = world.target().StateAt(t_s).position_m;
  Json errors = Json::object();
  const std::vector<std::string>& methods = scenario_.pipeline.methods;
  for (std::size_t i = 0; i < methods.size(); ++i) {
    const auto it = estimates.find(methods[i]);
    if (it == estimates.end()) continue;
    Json e = Entity("estimate/" + methods[i], ns);
    e["spheres"].push_back(Solid(Eigen::Isometry3d(Eigen::Translation3d(it->second)),
                                 Eigen::Vector3d::Constant(1.5), MethodColor(i)));
    e["texts"].push_back(Label(it->second + Eigen::Vector3d(0, 0, 1.5), methods[i]));
    Write("/estimates/" + methods[i], "foxglove.SceneUpdate", ns, SceneUpdate(Json::array({e})));
    errors[methods[i]] = (it->second - target).norm();
  }
  Write("/window_error", "uavsim.WindowError", ns,
        {{"timestamp", Time(ns)}, {"truth", Vec3(target)}, {"error_m", errors}});
}

core::Json McapRecorder::Summary() const {
  const results::McapStatistics& stats = writer_.statistics();
  Json topics = Json::object();
  for (const auto& [topic, id] : channels_) topics[topic] = stats.channel_message_counts.at(id);
  return {{"file", "recording.mcap"},
          {"bytes", writer_.bytes_written()},
          {"messages", stats.message_count},
          {"chunks", stats.chunk_count},
          {"topics", topics}};
}

void McapRecorder::Finish(const std::vector<channel::MessageRecord>& uplink_log) {
  const core::SimTime window_ns = core::Seconds(scenario_.pipeline.window_s);
  for (const channel::MessageRecord& m : uplink_log) {
    const bool arrived = m.t_arrival_ns >= 0;
    const std::uint64_t ns = Ns(m.t_capture_ns);
    const Json message = {
        {"timestamp", Time(ns)},
        {"node",
         m.node < scenario_.nodes.size() ? scenario_.nodes[m.node].id : std::to_string(m.node)},
        {"modality", core::ModalityName(m.modality)},
        {"sequence", m.sequence},
        {"bytes", m.payload_bytes},
        {"window", m.t_capture_ns / window_ns},
        {"status", channel::FateName(m.fate)},
        {"t_capture_s", core::ToSeconds(m.t_capture_ns)},
        {"t_arrival_s", arrived ? Json(core::ToSeconds(m.t_arrival_ns)) : Json(nullptr)},
        {"latency_s",
         arrived ? Json(core::ToSeconds(m.t_arrival_ns - m.t_capture_ns)) : Json(nullptr)}};
    Write("/uplink", "uavsim.UplinkMessage", ns, message);
  }
  writer_.Finish();
}

}  // namespace uavsim::sim
