#include "sensors/raycast_scene.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>

#include "core/interrupt.h"

namespace uavsim::sensors {
namespace {

constexpr unsigned kStaticInstanceId = 0;
// Rays cast between two looks at the termination flag.
constexpr std::size_t kInterruptPollRays = 1024;

// Embree reports errors through a C callback; throwing across it is not
// allowed, so the message is kept and thrown by the next checked call.
struct DeviceErrors {
  std::mutex mutex;
  std::string first;
};

extern "C" void OnEmbreeError(void* user, RTCError code, const char* message) {
  auto* errors = static_cast<DeviceErrors*>(user);
  std::lock_guard<std::mutex> lock(errors->mutex);
  if (errors->first.empty())
    errors->first =
        "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (message ? message : "");
}

void FillRay(const Ray& in, RTCRay& out) {
  out.org_x = in.origin_m.x();
  out.org_y = in.origin_m.y();
  out.org_z = in.origin_m.z();
  out.dir_x = in.direction.x();
  out.dir_y = in.direction.y();
  out.dir_z = in.direction.z();
  out.tnear = in.t_min;
  out.tfar = in.t_max;
  out.time = 0.0f;
  out.mask = 0xFFFFFFFFu;
  out.id = 0;
  out.flags = 0;
}

}  // namespace

struct RaycastScene::Impl {
  RTCDevice device = nullptr;
  RTCScene static_scene = nullptr;
  RTCScene top = nullptr;
  RTCScene static_top = nullptr;                 // the static instance alone
  std::vector<RTCScene> object_scenes;           // index k - 1 for moving object k
  std::vector<std::uint32_t> static_material;    // by geomID in static_scene
  std::vector<std::uint32_t> object_material;    // by object id (index 0 unused)
  std::vector<Eigen::Matrix3f> object_rotation;  // R_WO by object id, for normals
  // Shared by the views of one device: its error callback writes here.
  std::shared_ptr<DeviceErrors> errors = std::make_shared<DeviceErrors>();

  void Check(const char* what) {
    std::lock_guard<std::mutex> lock(errors->mutex);
    if (!errors->first.empty()) throw std::runtime_error(std::string(what) + ": " + errors->first);
  }

  ~Impl() {
    for (RTCScene s : object_scenes) rtcReleaseScene(s);
    if (top) rtcReleaseScene(top);
    if (static_top) rtcReleaseScene(static_top);
    if (static_scene) rtcReleaseScene(static_scene);
    if (device) rtcReleaseDevice(device);
  }

  // A triangle-mesh geometry with the mesh's vertices and indices copied in.
  RTCGeometry NewMesh(const core::TriangleMesh& mesh) {
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                          RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                          mesh.vertices_m.size()));
    auto* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned), mesh.triangles.size()));
    Check("rtcSetNewGeometryBuffer");
    for (std::size_t i = 0; i < mesh.vertices_m.size(); ++i)
      for (int k = 0; k < 3; ++k) v[3 * i + k] = mesh.vertices_m[i][k];
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        if (mesh.triangles[i][k] >= mesh.vertices_m.size())
          throw std::invalid_argument("mesh '" + mesh.name + "': triangle " + std::to_string(i) +
                                      " refers to a missing vertex");
        idx[3 * i + k] = mesh.triangles[i][k];
      }
    rtcCommitGeometry(geom);
    return geom;
  }

  void AttachInstance(RTCScene parent, RTCScene child, unsigned id, const Eigen::Isometry3d& X) {
    RTCGeometry inst = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(inst, child);
    rtcSetGeometryTimeStepCount(inst, 1);
    SetTransform(inst, X);
    rtcCommitGeometry(inst);
    rtcAttachGeometryByID(parent, inst, id);
    rtcReleaseGeometry(inst);
    Check("attach instance");
  }

  static void SetTransform(RTCGeometry inst, const Eigen::Isometry3d& X) {
    float m[12];  // 3x4 column major: the rotation's columns, then the translation
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 3; ++r) m[3 * c + r] = static_cast<float>(X.matrix()(r, c));
    rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, m);
  }

  RayHit ToHit(const RTCRayHit& rh, const Eigen::Vector3f& dir) const {
    RayHit h;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
    const unsigned inst = rh.hit.instID[0];
    h.t = rh.ray.tfar;
    h.object = static_cast<std::int32_t>(inst);
    // Embree gives the normal of an instanced hit in the object's own frame.
    Eigen::Vector3f n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    if (inst == kStaticInstanceId) {
      h.material = static_material[rh.hit.geomID];
    } else {
      h.material = object_material[inst];
      n = object_rotation[inst] * n;
    }
    const float len = n.norm();
    if (len > 0) n /= len;
    if (n.dot(dir) > 0) n = -n;
    h.normal_w = n;
    return h;
  }
};

RaycastScene::RaycastScene(const core::WorldGeometry& world)
    : impl_(std::make_unique<Impl>()), materials_(world.materials) {
  Impl& s = *impl_;
  s.device = rtcNewDevice("verbose=0");
  if (!s.device)
    throw std::runtime_error("Embree: cannot create a device (error " +
                             std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
  rtcSetDeviceErrorFunction(s.device, OnEmbreeError, s.errors.get());

  s.static_scene = rtcNewScene(s.device);
  rtcSetSceneBuildQuality(s.static_scene, RTC_BUILD_QUALITY_HIGH);
  for (const core::TriangleMesh& mesh : world.meshes) {
    if (mesh.triangles.empty()) continue;
    if (mesh.material >= materials_.size())
      throw std::invalid_argument("mesh '" + mesh.name + "': material " +
                                  std::to_string(mesh.material) + " does not exist");
    RTCGeometry geom = s.NewMesh(mesh);
    const unsigned id = rtcAttachGeometry(s.static_scene, geom);
    rtcReleaseGeometry(geom);
    if (s.static_material.size() <= id) s.static_material.resize(id + 1, 0);
    s.static_material[id] = mesh.material;
    static_triangles_ += mesh.triangles.size();
  }
  rtcCommitScene(s.static_scene);
  s.Check("building the static world");

  // The top level holds only instances, so moving objects re-commit a BVH of
  // a handful of boxes, never the city. The static-only top level is built
  // the same way, so the two differ only by the moving instances.
  for (RTCScene* top : {&s.top, &s.static_top}) {
    *top = rtcNewScene(s.device);
    rtcSetSceneFlags(*top, RTC_SCENE_FLAG_DYNAMIC);
    rtcSetSceneBuildQuality(*top, RTC_BUILD_QUALITY_LOW);
    s.AttachInstance(*top, s.static_scene, kStaticInstanceId, Eigen::Isometry3d::Identity());
    rtcCommitScene(*top);
  }
  s.object_material.push_back(0);
  s.object_rotation.push_back(Eigen::Matrix3f::Identity());
  s.Check("building the top level");
}

RaycastScene::~RaycastScene() = default;

RaycastScene::RaycastScene(const RaycastScene& other, ViewTag)
    : impl_(std::make_unique<Impl>()),
      materials_(other.materials_),
      poses_(other.poses_),
      object_radius_m_(other.object_radius_m_),
      moving_bounds_(other.moving_bounds_),
      static_triangles_(other.static_triangles_),
      time_s_(other.time_s_) {
  const Impl& o = *other.impl_;
  Impl& s = *impl_;
  // The BVHs of the city and of each moving object are shared (retained),
  // the top level of instances is the view's own.
  s.errors = o.errors;
  s.device = o.device;
  rtcRetainDevice(s.device);
  s.static_scene = o.static_scene;
  rtcRetainScene(s.static_scene);
  s.static_material = o.static_material;
  s.object_material = o.object_material;
  s.object_rotation = o.object_rotation;
  // The static-only top level never changes: shared too.
  s.static_top = o.static_top;
  rtcRetainScene(s.static_top);
  s.top = rtcNewScene(s.device);
  rtcSetSceneFlags(s.top, RTC_SCENE_FLAG_DYNAMIC);
  rtcSetSceneBuildQuality(s.top, RTC_BUILD_QUALITY_LOW);
  s.AttachInstance(s.top, s.static_scene, kStaticInstanceId, Eigen::Isometry3d::Identity());
  for (std::size_t k = 0; k < o.object_scenes.size(); ++k) {
    RTCScene child = o.object_scenes[k];
    rtcRetainScene(child);
    s.object_scenes.push_back(child);
    s.AttachInstance(s.top, child, static_cast<unsigned>(k + 1), poses_[k](time_s_));
  }
  rtcCommitScene(s.top);
  s.Check("making a view of the scene");
}

std::unique_ptr<RaycastScene> RaycastScene::NewView() const {
  return std::unique_ptr<RaycastScene>(new RaycastScene(*this, ViewTag{}));
}

int RaycastScene::AddMovingObject(const core::TriangleMesh& mesh, PoseFunction X_WO) {
  if (mesh.triangles.empty())
    throw std::invalid_argument("moving object '" + mesh.name + "' has no triangles");
  if (mesh.material >= materials_.size())
    throw std::invalid_argument("moving object '" + mesh.name + "': material " +
                                std::to_string(mesh.material) + " does not exist");
  Impl& s = *impl_;
  RTCScene child = rtcNewScene(s.device);
  rtcSetSceneBuildQuality(child, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geom = s.NewMesh(mesh);
  rtcAttachGeometry(child, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(child);
  s.object_scenes.push_back(child);
  const int id = static_cast<int>(s.object_scenes.size());
  const Eigen::Isometry3d X0 = X_WO(time_s_);
  s.AttachInstance(s.top, child, static_cast<unsigned>(id), X0);
  s.object_material.push_back(mesh.material);
  s.object_rotation.push_back(X0.linear().cast<float>());
  double radius_m = 0.0;
  for (const Eigen::Vector3f& v : mesh.vertices_m)
    radius_m = std::max(radius_m, v.cast<double>().norm());
  object_radius_m_.push_back(radius_m);
  moving_bounds_.push_back({X0.translation(), radius_m});
  poses_.push_back(std::move(X_WO));
  rtcCommitScene(s.top);
  s.Check("adding a moving object");
  return id;
}

void RaycastScene::SetTime(double t_s) {
  Impl& s = *impl_;
  for (std::size_t k = 0; k < poses_.size(); ++k) {
    const unsigned id = static_cast<unsigned>(k + 1);
    const Eigen::Isometry3d X = poses_[k](t_s);
    RTCGeometry inst = rtcGetGeometry(s.top, id);
    Impl::SetTransform(inst, X);
    rtcCommitGeometry(inst);
    s.object_rotation[id] = X.linear().cast<float>();
    moving_bounds_[k] = {X.translation(), object_radius_m_[k]};
  }
  if (!poses_.empty()) rtcCommitScene(s.top);
  s.Check("moving objects");
  time_s_ = t_s;
}

RayHit RaycastScene::Intersect(const Ray& ray) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  FillRay(ray, rh.ray);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->top, &ctx, &rh);
  return impl_->ToHit(rh, ray.direction);
}

void RaycastScene::IntersectMany(const Ray* rays, RayHit* hits, std::size_t count) const {
  IntersectPackets(false, rays, hits, count);
}

// Rays cast from inside the static world's bounds all enter the static
// instance, with tfar still infinite, in either top level: every box on the
// way to it contains the static bounds, and a ray's far distance shrinks
// only where it meets a moving object first. So Embree's choices inside the
// static BVH (octant groups, packet or single-ray traversal by the count of
// active rays) are the same, and so are the hits.
void RaycastScene::IntersectManyStatic(const Ray* rays, RayHit* hits, std::size_t count) const {
  IntersectPackets(true, rays, hits, count);
}

void RaycastScene::IntersectPackets(bool static_only, const Ray* rays, RayHit* hits,
                                    std::size_t count) const {
  RTCScene scene = static_only ? impl_->static_top : impl_->top;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  alignas(32) RTCRayHit8 packet;
  alignas(32) int valid[8];
  for (std::size_t base = 0; base < count; base += 8) {
    if (base % kInterruptPollRays == 0) core::ThrowIfInterrupted();
    const std::size_t n = std::min<std::size_t>(8, count - base);
    for (std::size_t i = 0; i < 8; ++i) {
      const Ray& r = rays[base + std::min(i, n - 1)];
      valid[i] = i < n ? -1 : 0;
      packet.ray.org_x[i] = r.origin_m.x();
      packet.ray.org_y[i] = r.origin_m.y();
      packet.ray.org_z[i] = r.origin_m.z();
      packet.ray.dir_x[i] = r.direction.x();
      packet.ray.dir_y[i] = r.direction.y();
      packet.ray.dir_z[i] = r.direction.z();
      packet.ray.tnear[i] = r.t_min;
      packet.ray.tfar[i] = r.t_max;
      packet.ray.time[i] = 0.0f;
      packet.ray.mask[i] = 0xFFFFFFFFu;
      packet.ray.id[i] = static_cast<unsigned>(i);
      packet.ray.flags[i] = 0;
      packet.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
      packet.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect8(valid, scene, &ctx, &packet);
    for (std::size_t i = 0; i < n; ++i) {
      RTCRayHit one;
      one.ray.tfar = packet.ray.tfar[i];
      one.hit.geomID = packet.hit.geomID[i];
      one.hit.instID[0] = packet.hit.instID[0][i];
      one.hit.Ng_x = packet.hit.Ng_x[i];
      one.hit.Ng_y = packet.hit.Ng_y[i];
      one.hit.Ng_z = packet.hit.Ng_z[i];
      hits[base + i] = impl_->ToHit(one, rays[base + i].direction);
    }
  }
}

Eigen::AlignedBox3d RaycastScene::static_bounds() const {
  RTCBounds b;
  rtcGetSceneBounds(impl_->static_scene, &b);
  return Eigen::AlignedBox3d(Eigen::Vector3d(b.lower_x, b.lower_y, b.lower_z),
                             Eigen::Vector3d(b.upper_x, b.upper_y, b.upper_z));
}

Eigen::Vector3d RaycastScene::PointVelocity(int object, const Eigen::Vector3d& p_W,
                                            double t_s) const {
  if (object <= 0 || static_cast<std::size_t>(object) > poses_.size())
    return Eigen::Vector3d::Zero();
  constexpr double kDt = 1e-3;
  const PoseFunction& X = poses_[static_cast<std::size_t>(object - 1)];
  const Eigen::Vector3d p_O = X(t_s).inverse() * p_W;  // the point in the object's own frame
  return (X(t_s + kDt) * p_O - X(t_s - kDt) * p_O) / (2.0 * kDt);
}

bool RaycastScene::Occluded(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            double eps_m) const {
  const Eigen::Vector3d d = b - a;
  const double len = d.norm();
  if (len <= 2 * eps_m) return false;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay ray;
  Ray r;
  r.origin_m = a.cast<float>();
  r.direction = d.cast<float>();
  r.t_min = static_cast<float>(eps_m / len);
  r.t_max = static_cast<float>(1.0 - eps_m / len);
  FillRay(r, ray);
  rtcOccluded1(impl_->top, &ctx, &ray);
  return ray.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace uavsim::sensors
