#include "core/world_geometry.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <exception>
#include <filesystem>
#include <string>
#include <utility>

#include "core/error.h"
#include "core/physical_constants.h"

namespace uavsim::core {

std::vector<Material> BuiltinMaterials() {
  // Broadband diffuse values; the 905 nm figures are what a LiDAR vendor's
  // reflectivity scale would report for the surface (Lambertian equivalent).
  std::vector<Material> m(kBuiltinMaterialCount);
  // Asphalt: solar reflectance 0.05 new to 0.10-0.15 weathered (LBNL Heat
  // Island Group, "Cool Pavements"); spectral libraries put it near 0.1 at 0.9 um.
  m[kMaterialGround] = {"asphalt", 0.10, 0.12, RadarClass::kGround};
  // Grey concrete: solar reflectance 0.35-0.45 new, ~0.25 weathered (LBNL);
  // cement spectra are flat to slightly rising into the NIR.
  m[kMaterialConcrete] = {"concrete", 0.35, 0.40, RadarClass::kConcrete};
  // Float glass, n = 1.52: Fresnel ((n-1)/(n+1))^2 = 4.3 % per face, reflected
  // specularly; the diffuse back-scatter a camera or LiDAR sees is small.
  m[kMaterialGlass] = {"glass", 0.08, 0.05, RadarClass::kGlass};
  // Grey-painted steel street furniture: paint reflectance 0.3-0.5 visible,
  // similar or higher at 905 nm (grey targets of LiDAR calibration boards).
  m[kMaterialMetal] = {"painted_metal", 0.40, 0.50, RadarClass::kMetal};
  // Green leaves: 0.05-0.10 in the visible (chlorophyll absorbs), 0.45-0.50 on
  // the NIR plateau past the red edge (Gates et al. 1965; PROSPECT leaf model).
  m[kMaterialFoliage] = {"foliage", 0.08, 0.45, RadarClass::kVegetation};
  // Carbon fibre and black ABS of consumer drones: near-black (0.05) in the
  // visible, ~10 % at 905 nm, the "dark target" class of LiDAR spec sheets.
  m[kMaterialDrone] = {"drone_carbon_plastic", 0.06, 0.10, RadarClass::kDrone};
  // Grey-brown plumage (pigeons, crows to gulls): ~0.2-0.3 visible; keratin
  // feathers without pigment absorption are brighter in the NIR.
  m[kMaterialBird] = {"bird_feathers", 0.25, 0.35, RadarClass::kBird};
  return m;
}

namespace {

using Eigen::Vector2f;
using Eigen::Vector3d;
using Eigen::Vector3f;

// Float pi for the float geometry (the float nearest core::kPi).
constexpr float kPi_f = static_cast<float>(kPi);

// City layout constants (metres). Street furniture keeps its real-world size
// whatever the block size; sidewalks shrink with small blocks.
constexpr double kMaxSidewalk_m = 4.0;   // also capped at 10 % of the block side
constexpr double kMaxGap_m = 0.5;        // least setback of a building inside its lot
constexpr double kPoleSpacing_m = 20.0;  // along each block side
constexpr float kPoleRadius_m = 0.1f;    // street-lamp pole, 0.2 m diameter
constexpr float kPoleHeight_m = 6.0f;
constexpr double kIntersectionClear_m = 5.0;  // sensors stand at intersection centres
constexpr double kGlassProbability = 0.3;
constexpr double kStreetTreeProbability = 0.5;  // plaza edges are fully planted
constexpr float kTrunkRadius_m = 0.15f;

std::uint32_t AddVertex(TriangleMesh& m, const Vector3f& v) {
  m.vertices_m.push_back(v);
  return static_cast<std::uint32_t>(m.vertices_m.size() - 1);
}

void AddQuad(TriangleMesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
  m.triangles.push_back({a, b, c});
  m.triangles.push_back({a, c, d});
}

// A closed box spanned by three orthogonal half axes that form a
// right-handed frame (so the fixed corner order below winds outward).
void AddBox(TriangleMesh& m, const Vector3f& center, const Vector3f& half_x, const Vector3f& half_y,
            const Vector3f& half_z) {
  std::uint32_t c[8];
  for (int i = 0; i < 8; ++i) {
    c[i] = AddVertex(m, center + ((i & 1) ? half_x : -half_x) + ((i & 2) ? half_y : -half_y) +
                            ((i & 4) ? half_z : -half_z));
  }
  AddQuad(m, c[0], c[4], c[6], c[2]);  // -x
  AddQuad(m, c[1], c[3], c[7], c[5]);  // +x
  AddQuad(m, c[0], c[1], c[5], c[4]);  // -y
  AddQuad(m, c[2], c[6], c[7], c[3]);  // +y
  AddQuad(m, c[0], c[2], c[3], c[1]);  // -z
  AddQuad(m, c[4], c[5], c[7], c[6]);  // +z
}

void AddAxisBox(TriangleMesh& m, const Vector3f& lo, const Vector3f& hi) {
  const Vector3f h = 0.5f * (hi - lo);
  AddBox(m, 0.5f * (lo + hi), {h.x(), 0, 0}, {0, h.y(), 0}, {0, 0, h.z()});
}

// A closed vertical prism over a convex polygon given counter-clockwise seen
// from above.
void AddPrism(TriangleMesh& m, const std::vector<Vector2f>& ring, float z0, float z1) {
  const auto n = static_cast<std::uint32_t>(ring.size());
  const auto base = static_cast<std::uint32_t>(m.vertices_m.size());
  for (const auto& p : ring) AddVertex(m, {p.x(), p.y(), z0});
  for (const auto& p : ring) AddVertex(m, {p.x(), p.y(), z1});
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::uint32_t k1 = (k + 1) % n;
    AddQuad(m, base + k, base + k1, base + n + k1, base + n + k);
  }
  for (std::uint32_t k = 1; k + 1 < n; ++k) {
    m.triangles.push_back({base, base + k + 1, base + k});              // bottom, facing down
    m.triangles.push_back({base + n, base + n + k, base + n + k + 1});  // top, facing up
  }
}

// An octagon with vertices on the axes, so its bounding box is exactly
// [cx - rx, cx + rx] x [cy - ry, cy + ry].
std::vector<Vector2f> Octagon(const Vector2f& c, float rx, float ry) {
  std::vector<Vector2f> ring;
  for (int k = 0; k < 8; ++k) {
    const float a = static_cast<float>(k) * kPi_f / 4.0f;
    ring.emplace_back(c.x() + rx * std::cos(a), c.y() + ry * std::sin(a));
  }
  // cos/sin of multiples of pi/4 are not exact in float; pin the extremes.
  ring[0].x() = c.x() + rx;
  ring[2] = {c.x(), c.y() + ry};
  ring[4] = {c.x() - rx, c.y()};
  ring[6] = {c.x(), c.y() - ry};
  return ring;
}

// Icosahedron of circumradius r (Kahler's vertex and face order, wound
// outward).
void AddIcosahedron(TriangleMesh& m, const Vector3f& center, float r) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  const Vector3f v[12] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  static constexpr std::uint32_t kFaces[20][3] = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  const auto base = static_cast<std::uint32_t>(m.vertices_m.size());
  for (const auto& p : v) AddVertex(m, center + r * p.normalized());
  for (const auto& f : kFaces) m.triangles.push_back({base + f[0], base + f[1], base + f[2]});
}

// Octahedron with half extents h along the axes.
void AddOctahedron(TriangleMesh& m, const Vector3f& center, const Vector3f& h) {
  const auto base = static_cast<std::uint32_t>(m.vertices_m.size());
  for (int axis = 0; axis < 3; ++axis) {
    for (float s : {1.0f, -1.0f}) {
      Vector3f p = center;
      p[axis] += s * h[axis];
      AddVertex(m, p);  // index base + 2 * axis + (s < 0)
    }
  }
  for (int sx = 0; sx < 2; ++sx) {
    for (int sy = 0; sy < 2; ++sy) {
      for (int sz = 0; sz < 2; ++sz) {
        const std::uint32_t x = base + sx, y = base + 2 + sy, z = base + 4 + sz;
        // An odd number of negative axes mirrors the octant, so swap to stay outward.
        if ((sx + sy + sz) % 2 == 0) {
          m.triangles.push_back({x, y, z});
        } else {
          m.triangles.push_back({x, z, y});
        }
      }
    }
  }
}

TriangleMesh GroundPlane(double size_m) {
  TriangleMesh g;
  g.name = "ground";
  g.material = kMaterialGround;
  const auto h = static_cast<float>(0.5 * size_m);
  g.vertices_m = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  g.triangles = {{0, 1, 2}, {0, 2, 3}};
  return g;
}

// With an even count there is no middle block: the two blocks either side
// of the centre line form the plaza along that axis.
bool IsMiddle(int index, int count) {
  if (count % 2 == 1) return index == count / 2;
  return index == count / 2 - 1 || index == count / 2;
}

// Splits [lo, hi] into n cells whose inner boundaries are jittered by up to
// 15 % of a cell, so neighbouring lots differ in size.
std::vector<double> JitteredSplits(double lo, double hi, int n, RngStream& rng) {
  std::vector<double> b(static_cast<std::size_t>(n) + 1);
  const double cell = (hi - lo) / n;
  for (int k = 0; k <= n; ++k) {
    b[static_cast<std::size_t>(k)] =
        lo + k * cell + ((k > 0 && k < n) ? rng.Uniform(-0.15, 0.15) * cell : 0.0);
  }
  return b;
}

struct GridLayout {
  const CityConfig& city;
  double pitch_m;     // block + street
  double sidewalk_m;  // strip along the block edge kept free of buildings
  double BlockCenter(int index, int count) const { return (index - 0.5 * (count - 1)) * pitch_m; }
  // Street centre lines are at (i - count / 2) * pitch, i = 0..count,
  // including the ring road around the city.
  double NearestStreet(double x, int count) const {
    const double i = std::clamp(std::round(x / pitch_m + 0.5 * count), 0.0, double(count));
    return (i - 0.5 * count) * pitch_m;
  }
  double DistanceToIntersection(double x, double y) const {
    return std::hypot(x - NearestStreet(x, city.blocks_x), y - NearestStreet(y, city.blocks_y));
  }
};

void AddBuildings(const GridLayout& layout, const Vector3d& block_center, RngStream rng,
                  const std::string& tag, WorldGeometry& world) {
  const CityConfig& city = layout.city;
  const double half_zone = 0.5 * city.block_size_m - layout.sidewalk_m;
  const int n = city.buildings_per_block;
  const int cols = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
  const int rows = (n + cols - 1) / cols;
  // Rows run along x or along y, a coin flip per block.
  const bool transpose = rng.Bernoulli(0.5);
  const int a_axis = transpose ? 1 : 0;
  const int b_axis = 1 - a_axis;
  const std::vector<double> row_edges =
      JitteredSplits(block_center[b_axis] - half_zone, block_center[b_axis] + half_zone, rows, rng);
  int k = 0;
  for (int r = 0; r < rows; ++r) {
    const int in_row = n / rows + (r < n % rows ? 1 : 0);
    const std::vector<double> col_edges = JitteredSplits(
        block_center[a_axis] - half_zone, block_center[a_axis] + half_zone, in_row, rng);
    for (int c = 0; c < in_row; ++c, ++k) {
      double lo[2], hi[2];
      lo[a_axis] = col_edges[static_cast<std::size_t>(c)];
      hi[a_axis] = col_edges[static_cast<std::size_t>(c) + 1];
      lo[b_axis] = row_edges[static_cast<std::size_t>(r)];
      hi[b_axis] = row_edges[static_cast<std::size_t>(r) + 1];
      // A gap on every side keeps neighbours apart: no coplanar faces for
      // the ray caster to flicker between, and one closed box per building.
      for (int axis = 0; axis < 2; ++axis) {
        const double span = hi[axis] - lo[axis];
        const double gap = std::min(kMaxGap_m, 0.05 * span);
        lo[axis] += gap + rng.Uniform(0.0, 0.12) * span;
        hi[axis] -= gap + rng.Uniform(0.0, 0.12) * span;
      }
      const double height_m = rng.Uniform(city.min_height_m, city.max_height_m);
      const bool glass = rng.Bernoulli(kGlassProbability);

      TriangleMesh b;
      b.name = "building_" + tag + "_" + std::to_string(k);
      b.material = glass ? kMaterialGlass : kMaterialConcrete;
      AddAxisBox(b, Vector3f(float(lo[0]), float(lo[1]), 0.0f),
                 Vector3f(float(hi[0]), float(hi[1]), float(height_m)));
      // Facades from the stored (float) corners so they coincide with the mesh.
      const Vector3d v_lo = b.vertices_m[0].cast<double>();
      const Vector3d v_hi = b.vertices_m[7].cast<double>();
      const Vector3d center = 0.5 * (v_lo + v_hi);
      const Vector3d half = 0.5 * (v_hi - v_lo);
      for (int axis = 0; axis < 2; ++axis) {
        for (double s : {-1.0, 1.0}) {
          Facade f;
          f.normal = s * Vector3d::Unit(axis);
          f.u_axis = Vector3d::UnitZ().cross(f.normal);  // so normal x u_axis is up
          f.center_m = center + s * half[axis] * Vector3d::Unit(axis);
          f.half_width_m = half[1 - axis];
          f.half_height_m = half.z();
          f.material = b.material;
          world.facades.push_back(f);
        }
      }
      world.meshes.push_back(std::move(b));
    }
  }
}

TriangleMesh MakePole(const Vector2f& xy, const std::string& name) {
  TriangleMesh p;
  p.name = name;
  p.material = kMaterialMetal;
  AddPrism(p, Octagon(xy, kPoleRadius_m, kPoleRadius_m), 0.0f, kPoleHeight_m);
  return p;
}

TriangleMesh MakeTree(const Vector2f& xy, float crown_radius_m, RngStream& rng,
                      const std::string& name) {
  TriangleMesh t;
  t.name = name;
  t.material = kMaterialFoliage;
  const auto trunk_m = static_cast<float>(rng.Uniform(2.0, 3.5));
  const float crown_z = trunk_m + 0.8f * crown_radius_m;
  // The trunk ends inside the crown (the icosahedron's inradius is 0.79 r).
  AddPrism(t, Octagon(xy, kTrunkRadius_m, kTrunkRadius_m), 0.0f, trunk_m + 0.5f * crown_radius_m);
  AddIcosahedron(t, {xy.x(), xy.y(), crown_z}, crown_radius_m);
  return t;
}

// Poles and trees stand on each block's sidewalk, in slots along every side:
// poles at odd multiples of side / (2 n), trees at odd multiples of
// side / (4 n), so the two never share a slot.
void AddStreetFurniture(const GridLayout& layout, const Vector3d& block_center, bool plaza,
                        RngStream rng, const std::string& tag, WorldGeometry& world) {
  const CityConfig& city = layout.city;
  const double side = city.block_size_m;
  const int n = std::max(1, static_cast<int>(std::lround(side / kPoleSpacing_m)));
  auto clear = [&](const Vector3d& p, double radius_m) {
    return layout.DistanceToIntersection(p.x(), p.y()) >= kIntersectionClear_m + radius_m;
  };
  const Vector3d outward[4] = {-Vector3d::UnitY(), Vector3d::UnitX(), Vector3d::UnitY(),
                               -Vector3d::UnitX()};
  int pole_k = 0, tree_k = 0;
  for (int s = 0; s < 4; ++s) {
    const Vector3d along = Vector3d::UnitZ().cross(outward[s]);
    const Vector3d edge = block_center + 0.5 * side * outward[s];
    if (city.poles) {
      for (int k = 0; k < n; ++k) {
        const Vector3d p = edge - 0.25 * layout.sidewalk_m * outward[s] +
                           (-0.5 * side + (2 * k + 1) * side / (2.0 * n)) * along;
        if (!clear(p, kPoleRadius_m)) continue;
        world.meshes.push_back(
            MakePole(p.head<2>().cast<float>(), "pole_" + tag + "_" + std::to_string(pole_k++)));
      }
    }
    if (city.trees) {
      for (int k = 0; k < 2 * n; ++k) {
        // Draw for every slot, planted or not, so the layout of one slot
        // does not depend on another's outcome.
        const bool planted = rng.Bernoulli(kStreetTreeProbability) || plaza;
        // Crowns stay on the sidewalk: clear of the buildings and the roadway.
        const auto crown_m = static_cast<float>(rng.Uniform(0.75, 1.0) * 0.5 * layout.sidewalk_m);
        RngStream tree_rng = rng.Derive("tree" + std::to_string(s) + "_" + std::to_string(k));
        const Vector3d p = edge - 0.5 * layout.sidewalk_m * outward[s] +
                           (-0.5 * side + (2 * k + 1) * side / (4.0 * n)) * along;
        if (!planted || !clear(p, crown_m)) continue;
        world.meshes.push_back(MakeTree(p.head<2>().cast<float>(), crown_m, tree_rng,
                                        "tree_" + tag + "_" + std::to_string(tree_k++)));
      }
    }
  }
}

void BuildGridCity(const CityConfig& city, const RngStream& rng, WorldGeometry& world) {
  const GridLayout layout{city, city.block_size_m + city.street_width_m,
                          std::min(kMaxSidewalk_m, 0.1 * city.block_size_m)};
  for (int bx = 0; bx < city.blocks_x; ++bx) {
    for (int by = 0; by < city.blocks_y; ++by) {
      const Vector3d center(layout.BlockCenter(bx, city.blocks_x),
                            layout.BlockCenter(by, city.blocks_y), 0.0);
      const std::string tag = std::to_string(bx) + "_" + std::to_string(by);
      // One stream per block and purpose: changing the grid size or turning
      // trees off leaves the other blocks' buildings where they were.
      const bool plaza =
          city.central_plaza && IsMiddle(bx, city.blocks_x) && IsMiddle(by, city.blocks_y);
      if (!plaza) AddBuildings(layout, center, rng.Derive("buildings/" + tag), tag, world);
      AddStreetFurniture(layout, center, plaza, rng.Derive("furniture/" + tag), tag, world);
    }
  }
}

std::uint32_t MaterialFromName(std::string name) {
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  auto has = [&](const char* word) { return name.find(word) != std::string::npos; };
  if (has("glass") || has("window")) return kMaterialGlass;
  if (has("metal") || has("steel")) return kMaterialMetal;
  if (has("tree") || has("foliage") || has("leaf") || has("leaves") || has("vegetation"))
    return kMaterialFoliage;
  if (has("asphalt") || has("road")) return kMaterialGround;
  return kMaterialConcrete;
}

// One TriangleMesh per mesh reference in the node tree, with the node's
// accumulated transform applied (identity for OBJ and PLY; baked by hand
// rather than by aiProcess_PreTransformVertices, which merges objects by
// material and loses their names).
void CollectMeshes(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
                   const CityConfig& city, const std::string& file, WorldGeometry& world) {
  const aiMatrix4x4 X = parent * node.mTransformation;
  const bool mirrored = X.Determinant() < 0.0f;  // keeps counter-clockwise winding outward
  const auto scale = static_cast<float>(city.scale);
  const Vector3f offset = city.offset_m.cast<float>();
  for (unsigned i = 0; i < node.mNumMeshes; ++i) {
    const aiMesh& in = *scene.mMeshes[node.mMeshes[i]];
    TriangleMesh out;
    out.name = in.mName.length > 0     ? in.mName.C_Str()
               : node.mName.length > 0 ? node.mName.C_Str()
                                       : "mesh_" + std::to_string(world.meshes.size());
    aiString material_name;
    if (in.mMaterialIndex < scene.mNumMaterials &&
        scene.mMaterials[in.mMaterialIndex]->Get(AI_MATKEY_NAME, material_name) == AI_SUCCESS)
      out.material = MaterialFromName(material_name.C_Str());
    for (unsigned f = 0; f < in.mNumFaces; ++f) {
      const aiFace& face = in.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines of mixed files
      for (unsigned k = 0; k < 3; ++k)
        if (face.mIndices[k] >= in.mNumVertices)
          throw ConfigError(file, "/world/city/path",
                            "face " + std::to_string(f) + " of mesh \"" + out.name +
                                "\" refers to vertex " + std::to_string(face.mIndices[k]) + " of " +
                                std::to_string(in.mNumVertices));
      out.triangles.push_back(
          {face.mIndices[0], face.mIndices[mirrored ? 2 : 1], face.mIndices[mirrored ? 1 : 2]});
    }
    if (out.triangles.empty()) continue;
    out.vertices_m.reserve(in.mNumVertices);
    for (unsigned v = 0; v < in.mNumVertices; ++v) {
      const aiVector3D p = X * in.mVertices[v];
      const Vector3f q = scale * Vector3f(p.x, p.y, p.z) + offset;
      if (!q.allFinite())
        throw ConfigError(file, "/world/city/path",
                          "vertex " + std::to_string(v) + " of mesh \"" + out.name +
                              "\" is not finite after scale and offset");
      // Embree works in float: beyond 1e6 m its hits lose centimetres.
      if (q.cwiseAbs().maxCoeff() > 1e6f)
        throw ConfigError(file, "/world/city/path",
                          "vertex " + std::to_string(v) + " of mesh \"" + out.name +
                              "\" lies more than 1e6 m from the origin after scale and offset");
      out.vertices_m.push_back(q);
    }
    world.meshes.push_back(std::move(out));
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c)
    CollectMeshes(scene, *node.mChildren[c], X, city, file, world);
}

void ImportMesh(const CityConfig& city, const std::string& base_dir, WorldGeometry& world) {
  namespace fs = std::filesystem;
  const std::string file = (fs::path(base_dir) / city.path).lexically_normal().string();
  const char* pointer = "/world/city/path";
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw ConfigError(file, pointer, "mesh file not found");
  Assimp::Importer importer;
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(file, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                        aiProcess_ValidateDataStructure);
  } catch (const std::exception& e) {
    throw ConfigError(file, pointer, std::string("cannot read the mesh: ") + e.what());
  }
  if (!scene || !scene->mRootNode)
    throw ConfigError(file, pointer,
                      std::string("cannot read the mesh: ") + importer.GetErrorString());
  const std::size_t first = world.meshes.size();
  CollectMeshes(*scene, *scene->mRootNode, aiMatrix4x4(), city, file, world);
  if (world.meshes.size() == first) throw ConfigError(file, pointer, "the mesh has no triangles");
}

}  // namespace

WorldGeometry BuildWorldGeometry(const WorldConfig& config, const std::string& base_dir,
                                 RngStream rng) {
  WorldGeometry world;
  world.meshes.push_back(GroundPlane(config.ground_size_m));
  switch (config.city.type) {
    case CityType::kOpen:
      break;
    case CityType::kGrid:
      BuildGridCity(config.city, rng, world);
      break;
    case CityType::kMesh:
      ImportMesh(config.city, base_dir, world);
      break;
  }
  return world;
}

TriangleMesh MakeQuadrotorMesh(const Vector3d& size_m) {
  TriangleMesh m;
  m.name = "quadrotor";
  m.material = kMaterialDrone;
  const Vector3f s = size_m.cast<float>();
  const Vector3f half = 0.5f * s;
  // Proportions of a 0.5 m class quadrotor: rotors of 0.44 x span at the
  // corners (they set the x-y extent), body below them (sets the bottom).
  const float rotor_rx = 0.22f * s.x(), rotor_ry = 0.22f * s.y();
  const float rotor_z0 = 0.4f * s.z(), rotor_z1 = half.z();
  AddAxisBox(m, {-0.2f * s.x(), -0.2f * s.y(), -half.z()},
             {0.2f * s.x(), 0.2f * s.y(), 0.3f * s.z()});
  const float arm_half_w = 0.03f * std::min(s.x(), s.y());
  const float arm_half_h = 0.5f * (rotor_z0 - 0.25f * s.z());
  const float arm_zc = rotor_z0 - arm_half_h;
  for (float sx : {1.0f, -1.0f}) {
    for (float sy : {1.0f, -1.0f}) {
      const Vector2f c(sx * (half.x() - rotor_rx), sy * (half.y() - rotor_ry));
      AddPrism(m, Octagon(c, rotor_rx, rotor_ry), rotor_z0, rotor_z1);
      // Arm from the hub to the rotor centre, in a right-handed frame.
      const Vector3f dir = Vector3f(c.x(), c.y(), 0.0f).normalized();
      const Vector3f side = Vector3f::UnitZ().cross(dir);
      AddBox(m, Vector3f(0.5f * c.x(), 0.5f * c.y(), arm_zc), 0.5f * c.norm() * dir,
             arm_half_w * side, {0.0f, 0.0f, arm_half_h});
    }
  }
  return m;
}

TriangleMesh MakeBirdMesh(double span_m) {
  TriangleMesh m;
  m.name = "bird";
  m.material = kMaterialBird;
  const auto b = static_cast<float>(span_m);
  // Pigeon-like proportions: body about half the span long.
  AddOctahedron(m, Vector3f::Zero(), {0.25f * b, 0.06f * b, 0.05f * b});
  // Wings are thin triangular prisms rooted inside the body, swept back,
  // with their tips at +-span / 2.
  const float thick = 0.005f * b;
  for (float s : {1.0f, -1.0f}) {
    std::vector<Vector2f> wing = {
        {0.10f * b, s * 0.03f * b}, {-0.08f * b, s * 0.03f * b}, {-0.12f * b, s * 0.5f * b}};
    const Vector2f e1 = wing[1] - wing[0], e2 = wing[2] - wing[0];
    if (e1.x() * e2.y() - e1.y() * e2.x() < 0.0f)
      std::swap(wing[1], wing[2]);  // AddPrism wants CCW
    AddPrism(m, wing, -thick, thick);
  }
  return m;
}

}  // namespace uavsim::core
