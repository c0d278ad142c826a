// The static world and the moving objects' shapes as plain data: triangle
// meshes with a material each, plus the planar building faces that the
// image method reflects radio paths from. Built from a WorldConfig; turned
// into an Embree scene by sensors/raycast_scene. No ray casting here.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/rng.h"
#include "core/world.h"

namespace uavsim::core {

// How a surface scatters a radar's wave; sets its RCS model (sensors/).
enum class RadarClass { kGround, kConcrete, kGlass, kMetal, kVegetation, kDrone, kBird };

struct Material {
  std::string name;
  double albedo = 0.3;              // visible-band Lambertian albedo
  double lidar_reflectivity = 0.3;  // Lambertian reflectivity at 905 nm
  RadarClass radar_class = RadarClass::kConcrete;
};

// Indices into WorldGeometry::materials of the built-in materials, in order.
enum BuiltinMaterial : std::uint32_t {
  kMaterialGround = 0,    // asphalt
  kMaterialConcrete = 1,  // building walls and roofs
  kMaterialGlass = 2,     // glazed facades
  kMaterialMetal = 3,     // poles
  kMaterialFoliage = 4,   // trees
  kMaterialDrone = 5,     // UAV body: dark carbon and plastic
  kMaterialBird = 6,
  kBuiltinMaterialCount = 7,
};
std::vector<Material> BuiltinMaterials();

struct TriangleMesh {
  std::string name;
  std::vector<Eigen::Vector3f> vertices_m;
  std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from outside
  std::uint32_t material = kMaterialConcrete;
};

// A planar rectangle: a building face, for the image method.
struct Facade {
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();  // unit, pointing out of the building
  Eigen::Vector3d u_axis = Eigen::Vector3d::UnitY();  // unit, in the plane, horizontal
  double half_width_m = 0.0;                          // along u_axis
  double half_height_m = 0.0;                         // along normal x u_axis (vertical)
  std::uint32_t material = kMaterialConcrete;
};

struct WorldGeometry {
  std::vector<Material> materials = BuiltinMaterials();
  std::vector<TriangleMesh> meshes;  // static: ground, buildings, poles, trees, imported mesh
  std::vector<Facade> facades;       // vertical building faces (grid cities; empty for meshes)
};

// Builds the static world. Grid cities draw building footprints and heights
// from `rng` (the world's own stream). A mesh city is read from
// config.city.path relative to `base_dir` (OBJ or PLY), scaled and offset;
// throws ConfigError naming "/world/city/path" if it cannot be read.
WorldGeometry BuildWorldGeometry(const WorldConfig& config, const std::string& base_dir,
                                 RngStream rng);

// A quadrotor-like mesh (body, four arms, four rotor discs) centred on the
// origin, filling the box size_m (x forward, y left, z up).
TriangleMesh MakeQuadrotorMesh(const Eigen::Vector3d& size_m);
// A bird-like mesh (body and two wings) of wingspan span_m, x forward.
TriangleMesh MakeBirdMesh(double span_m);

}  // namespace uavsim::core
