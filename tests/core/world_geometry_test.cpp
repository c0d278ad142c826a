#include "core/world_geometry.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/rng.h"

namespace uavsim::core {
namespace {

using Eigen::Vector3d;
namespace fs = std::filesystem;

// A fresh folder for mesh files, removed when the test case ends.
struct ScratchDir {
  std::string path;
  ScratchDir() {
    char name[] = "/tmp/uavsim-world-geometry-XXXXXX";
    REQUIRE(mkdtemp(name) != nullptr);
    path = name;
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  void Write(const std::string& file, const std::string& text) const {
    std::ofstream(path + "/" + file, std::ios::binary) << text;
  }
};

struct Box {
  Vector3d lo = Vector3d::Constant(1e30);
  Vector3d hi = Vector3d::Constant(-1e30);
  Vector3d Center() const { return 0.5 * (lo + hi); }
  Vector3d Size() const { return hi - lo; }
};

Box BoundsOf(const TriangleMesh& m) {
  Box b;
  for (const auto& v : m.vertices_m) {
    b.lo = b.lo.cwiseMin(v.cast<double>());
    b.hi = b.hi.cwiseMax(v.cast<double>());
  }
  return b;
}

bool StartsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

std::vector<const TriangleMesh*> MeshesNamed(const WorldGeometry& w, const std::string& prefix) {
  std::vector<const TriangleMesh*> out;
  for (const auto& m : w.meshes)
    if (StartsWith(m.name, prefix)) out.push_back(&m);
  return out;
}

// Closed and consistently wound: every directed edge appears once and its
// reverse once, so each edge is shared by exactly two triangles that
// traverse it in opposite directions.
bool IsClosedManifold(const TriangleMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& t : m.triangles)
    for (int i = 0; i < 3; ++i) ++directed[{t[i], t[(i + 1) % 3]}];
  for (const auto& [edge, count] : directed) {
    if (count != 1) return false;
    const auto reverse = directed.find({edge.second, edge.first});
    if (reverse == directed.end() || reverse->second != 1) return false;
  }
  return !m.triangles.empty();
}

// Divergence theorem: sum over triangles of v0 . (v1 x v2) / 6; positive for
// an outward-wound closed surface.
double SignedVolume(const TriangleMesh& m, const std::vector<std::size_t>& triangles) {
  double v = 0.0;
  for (std::size_t i : triangles) {
    const auto& t = m.triangles[i];
    const Vector3d a = m.vertices_m[t[0]].cast<double>();
    const Vector3d b = m.vertices_m[t[1]].cast<double>();
    const Vector3d c = m.vertices_m[t[2]].cast<double>();
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

double SignedVolume(const TriangleMesh& m) {
  std::vector<std::size_t> all(m.triangles.size());
  std::iota(all.begin(), all.end(), 0);
  return SignedVolume(m, all);
}

// Triangle indices of each connected component (sharing vertices).
std::vector<std::vector<std::size_t>> Components(const TriangleMesh& m) {
  std::vector<std::uint32_t> parent(m.vertices_m.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& t : m.triangles) {
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  std::map<std::uint32_t, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < m.triangles.size(); ++i) groups[find(m.triangles[i][0])].push_back(i);
  std::vector<std::vector<std::size_t>> out;
  for (auto& [root, tris] : groups) out.push_back(std::move(tris));
  return out;
}

void RequireClosedOutward(const TriangleMesh& m) {
  INFO(m.name);
  REQUIRE(IsClosedManifold(m));
  for (const auto& component : Components(m)) REQUIRE(SignedVolume(m, component) > 0.0);
}

WorldConfig GridConfig() {
  WorldConfig c;  // the default: 3 x 3 blocks of 40 m, 20 m streets
  c.city.type = CityType::kGrid;
  return c;
}

WorldGeometry Build(const WorldConfig& c, std::uint64_t seed = 1, const std::string& dir = ".") {
  return BuildWorldGeometry(c, dir, RngStream(seed, "world"));
}

double BlockCenter(int index, int count, const CityConfig& c) {
  return (index - 0.5 * (count - 1)) * (c.block_size_m + c.street_width_m);
}

// Index of the block whose square contains x, or -1 if x lies in a street.
int BlockIndexOf(double x, int count, const CityConfig& c) {
  for (int i = 0; i < count; ++i)
    if (std::abs(x - BlockCenter(i, count, c)) <= 0.5 * c.block_size_m + 1e-4) return i;
  return -1;
}

// Street centre lines, including the ring road around the city.
std::vector<double> StreetLines(int count, const CityConfig& c) {
  std::vector<double> s;
  for (int i = 0; i <= count; ++i)
    s.push_back((i - 0.5 * count) * (c.block_size_m + c.street_width_m));
  return s;
}

double NearestIntersection_m(const Vector3d& p, const CityConfig& c) {
  double best = 1e30;
  for (double x : StreetLines(c.blocks_x, c))
    for (double y : StreetLines(c.blocks_y, c))
      best = std::min(best, std::hypot(p.x() - x, p.y() - y));
  return best;
}

// Which blocks hold buildings, with how many.
std::map<std::pair<int, int>, int> BuildingsPerBlock(const WorldGeometry& w, const CityConfig& c) {
  std::map<std::pair<int, int>, int> n;
  for (const auto* b : MeshesNamed(w, "building_")) {
    const Box box = BoundsOf(*b);
    ++n[{BlockIndexOf(box.Center().x(), c.blocks_x, c),
         BlockIndexOf(box.Center().y(), c.blocks_y, c)}];
  }
  return n;
}

TEST_CASE("BuiltinMaterials: one per index, physically plausible", "[core]") {
  const auto m = BuiltinMaterials();
  REQUIRE(m.size() == kBuiltinMaterialCount);
  for (const auto& x : m) {
    INFO(x.name);
    CHECK(!x.name.empty());
    CHECK(x.albedo > 0.0);
    CHECK(x.albedo < 1.0);
    CHECK(x.lidar_reflectivity > 0.0);
    CHECK(x.lidar_reflectivity < 1.0);
  }
  CHECK(m[kMaterialGround].albedo == Approx(0.1).margin(0.05));
  CHECK(m[kMaterialConcrete].albedo >= 0.3);
  CHECK(m[kMaterialConcrete].albedo <= 0.4);
  // The red edge: leaves are dark in the visible and bright at 905 nm.
  CHECK(m[kMaterialFoliage].lidar_reflectivity >= 0.4);
  CHECK(m[kMaterialFoliage].albedo < 0.15);
  CHECK(m[kMaterialDrone].albedo <= 0.1);
  CHECK(m[kMaterialDrone].lidar_reflectivity == Approx(0.1).margin(0.03));
  CHECK(m[kMaterialGround].radar_class == RadarClass::kGround);
  CHECK(m[kMaterialGlass].radar_class == RadarClass::kGlass);
  CHECK(m[kMaterialMetal].radar_class == RadarClass::kMetal);
  CHECK(m[kMaterialFoliage].radar_class == RadarClass::kVegetation);
  CHECK(m[kMaterialDrone].radar_class == RadarClass::kDrone);
  CHECK(m[kMaterialBird].radar_class == RadarClass::kBird);
}

TEST_CASE("BuildWorldGeometry: open field is one upward ground square", "[core]") {
  WorldConfig c;
  c.city.type = CityType::kOpen;
  c.ground_size_m = 300.0;
  const WorldGeometry w = Build(c);
  REQUIRE(w.meshes.size() == 1);
  CHECK(w.facades.empty());
  CHECK(w.materials.size() == kBuiltinMaterialCount);
  const TriangleMesh& g = w.meshes[0];
  CHECK(g.material == kMaterialGround);
  REQUIRE(g.triangles.size() == 2);
  const Box b = BoundsOf(g);
  CHECK(b.lo.isApprox(Vector3d(-150, -150, 0)));
  CHECK(b.hi.isApprox(Vector3d(150, 150, 0)));
  double area_m2 = 0.0;
  for (const auto& t : g.triangles) {
    const Vector3d n = (g.vertices_m[t[1]] - g.vertices_m[t[0]])
                           .cross(g.vertices_m[t[2]] - g.vertices_m[t[0]])
                           .cast<double>();
    CHECK(n.z() > 0.0);  // counter-clockwise seen from above
    area_m2 += 0.5 * n.norm();
  }
  CHECK(area_m2 == Approx(300.0 * 300.0));
}

TEST_CASE("BuildWorldGeometry: grid buildings are closed boxes inside their blocks", "[core]") {
  WorldConfig c = GridConfig();
  int per_block = 4;
  SECTION("default 3 x 3, four per block") {}
  SECTION("one per block") { per_block = 1; }
  SECTION("three per block, narrow streets") {
    per_block = 3;
    c.city.street_width_m = 8.0;
  }
  SECTION("seven per block, 4 x 2 grid, small blocks") {
    per_block = 7;
    c.city.blocks_x = 4;
    c.city.blocks_y = 2;
    c.city.block_size_m = 12.0;
  }
  c.city.buildings_per_block = per_block;
  const CityConfig& city = c.city;
  const WorldGeometry w = Build(c, 7);

  REQUIRE(w.meshes.front().name == "ground");
  const auto buildings = MeshesNamed(w, "building_");
  std::map<std::pair<int, int>, std::vector<Box>> by_block;
  for (const auto* b : buildings) {
    INFO(b->name);
    CHECK((b->material == kMaterialConcrete || b->material == kMaterialGlass));
    REQUIRE(b->triangles.size() == 12);
    RequireClosedOutward(*b);
    const Box box = BoundsOf(*b);
    const Vector3d size = box.Size();
    CHECK(SignedVolume(*b) == Approx(size.x() * size.y() * size.z()).epsilon(1e-5));
    CHECK(box.lo.z() == 0.0);
    CHECK(size.z() >= city.min_height_m - 1e-4);
    CHECK(size.z() <= city.max_height_m + 1e-4);
    // Inside one block square, so off every street.
    const int bx = BlockIndexOf(box.Center().x(), city.blocks_x, city);
    const int by = BlockIndexOf(box.Center().y(), city.blocks_y, city);
    REQUIRE(bx >= 0);
    REQUIRE(by >= 0);
    const double half = 0.5 * city.block_size_m;
    CHECK(box.lo.x() > BlockCenter(bx, city.blocks_x, city) - half);
    CHECK(box.hi.x() < BlockCenter(bx, city.blocks_x, city) + half);
    CHECK(box.lo.y() > BlockCenter(by, city.blocks_y, city) - half);
    CHECK(box.hi.y() < BlockCenter(by, city.blocks_y, city) + half);
    by_block[{bx, by}].push_back(box);
  }
  // Every block but the plaza(s) holds exactly buildings_per_block lots that
  // do not overlap.
  const int plaza_x = city.blocks_x % 2 ? 1 : 2, plaza_y = city.blocks_y % 2 ? 1 : 2;
  CHECK(by_block.size() == std::size_t(city.blocks_x * city.blocks_y - plaza_x * plaza_y));
  for (const auto& [block, boxes] : by_block) {
    CHECK(boxes.size() == std::size_t(per_block));
    for (std::size_t i = 0; i < boxes.size(); ++i)
      for (std::size_t j = i + 1; j < boxes.size(); ++j) {
        const bool apart = boxes[i].hi.x() < boxes[j].lo.x() || boxes[j].hi.x() < boxes[i].lo.x() ||
                           boxes[i].hi.y() < boxes[j].lo.y() || boxes[j].hi.y() < boxes[i].lo.y();
        CHECK(apart);
      }
  }
}

TEST_CASE("BuildWorldGeometry: heights spread over [min, max]", "[core]") {
  WorldConfig c = GridConfig();
  c.city.blocks_x = c.city.blocks_y = 9;
  c.city.min_height_m = 12.0;
  c.city.max_height_m = 20.0;
  double lo = 1e30, hi = -1e30, sum = 0.0;
  const WorldGeometry w = Build(c);
  const auto buildings = MeshesNamed(w, "building_");
  for (const auto* b : buildings) {
    const double h = BoundsOf(*b).hi.z();
    lo = std::min(lo, h), hi = std::max(hi, h), sum += h;
  }
  REQUIRE(buildings.size() == 80 * 4);
  CHECK(lo >= 12.0);
  CHECK(hi <= 20.0);
  // Uniform on [12, 20]: the extremes of 320 draws lie within 0.3 m of the
  // ends with probability 1 - 2 (1 - 0.3/8)^320 > 0.99999; the mean has
  // standard error 8 / sqrt(12 * 320) = 0.13 m.
  CHECK(lo < 12.3);
  CHECK(hi > 19.7);
  CHECK(sum / buildings.size() == Approx(16.0).margin(0.6));
}

TEST_CASE("BuildWorldGeometry: same seed gives the same city, another seed another", "[core]") {
  const WorldConfig c = GridConfig();
  const WorldGeometry a = Build(c, 1), b = Build(c, 1), other = Build(c, 2);
  REQUIRE(a.meshes.size() == b.meshes.size());
  for (std::size_t i = 0; i < a.meshes.size(); ++i) {
    CHECK(a.meshes[i].name == b.meshes[i].name);
    CHECK(a.meshes[i].material == b.meshes[i].material);
    CHECK(a.meshes[i].vertices_m == b.meshes[i].vertices_m);
    CHECK(a.meshes[i].triangles == b.meshes[i].triangles);
  }
  REQUIRE(a.facades.size() == b.facades.size());
  for (std::size_t i = 0; i < a.facades.size(); ++i)
    CHECK(a.facades[i].center_m == b.facades[i].center_m);

  const auto ba = MeshesNamed(a, "building_"), bo = MeshesNamed(other, "building_");
  REQUIRE(ba.size() == bo.size());
  int differ = 0;
  for (std::size_t i = 0; i < ba.size(); ++i) differ += ba[i]->vertices_m != bo[i]->vertices_m;
  CHECK(differ == int(ba.size()));
}

TEST_CASE("BuildWorldGeometry: central plaza leaves the middle block(s) empty", "[core]") {
  WorldConfig c = GridConfig();
  SECTION("odd: the centre block, planted around its edge") {
    const WorldGeometry w = Build(c);
    const auto n = BuildingsPerBlock(w, c.city);
    CHECK(n.count({1, 1}) == 0);
    CHECK(n.size() == 8);
    // No building reaches into the plaza square, and trees line it.
    for (const auto* b : MeshesNamed(w, "building_")) {
      const Box box = BoundsOf(*b);
      CHECK((box.lo.x() > 20.0 || box.hi.x() < -20.0 || box.lo.y() > 20.0 || box.hi.y() < -20.0));
    }
    CHECK(MeshesNamed(w, "tree_1_1_").size() == 16);
  }
  SECTION("without a plaza the centre block is built") {
    c.city.central_plaza = false;
    const auto n = BuildingsPerBlock(Build(c), c.city);
    CHECK(n.size() == 9);
    CHECK(n.at({1, 1}) == 4);
  }
  SECTION("even by odd: the two blocks either side of the centre line") {
    c.city.blocks_x = 4;
    const auto n = BuildingsPerBlock(Build(c), c.city);
    CHECK(n.size() == 10);
    CHECK(n.count({1, 1}) == 0);
    CHECK(n.count({2, 1}) == 0);
  }
  SECTION("even by even: the four blocks around the central intersection") {
    c.city.blocks_x = 4;
    c.city.blocks_y = 4;
    const auto n = BuildingsPerBlock(Build(c), c.city);
    CHECK(n.size() == 12);
    for (int x : {1, 2})
      for (int y : {1, 2}) CHECK(n.count({x, y}) == 0);
  }
}

TEST_CASE("BuildWorldGeometry: one outward facade per building wall", "[core]") {
  const WorldConfig c = GridConfig();
  const WorldGeometry w = Build(c, 3);
  const auto buildings = MeshesNamed(w, "building_");
  REQUIRE(w.facades.size() == 4 * buildings.size());
  std::vector<int> walls_seen(buildings.size(), 0);
  for (const Facade& f : w.facades) {
    CHECK(f.normal.norm() == Approx(1.0));
    CHECK(f.u_axis.norm() == Approx(1.0));
    CHECK(f.u_axis.z() == Approx(0.0).margin(1e-12));
    CHECK(f.normal.dot(f.u_axis) == Approx(0.0).margin(1e-12));
    CHECK(f.normal.cross(f.u_axis).isApprox(Vector3d::UnitZ()));
    // The building whose wall this is: the facade centre lies on its surface.
    int owner = -1, axis = -1;
    for (std::size_t i = 0; i < buildings.size() && owner < 0; ++i) {
      const Box b = BoundsOf(*buildings[i]);
      if (((f.center_m - b.lo).array() < -1e-4).any() || ((f.center_m - b.hi).array() > 1e-4).any())
        continue;
      for (int a = 0; a < 2; ++a)
        if (std::abs(f.center_m[a] - b.lo[a]) < 1e-4 || std::abs(f.center_m[a] - b.hi[a]) < 1e-4)
          owner = int(i), axis = a;
    }
    REQUIRE(owner >= 0);
    const Box b = BoundsOf(*buildings[std::size_t(owner)]);
    INFO(buildings[std::size_t(owner)]->name);
    CHECK(f.material == buildings[std::size_t(owner)]->material);
    // Outward: pointing away from the box centre, along the wall's axis.
    CHECK(std::abs(f.normal[axis]) == Approx(1.0));
    CHECK((f.center_m - b.Center()).dot(f.normal) > 0.0);
    const Vector3d size = b.Size();
    const double wall_area_m2 = size[1 - axis] * size.z();
    CHECK(4.0 * f.half_width_m * f.half_height_m == Approx(wall_area_m2).epsilon(1e-6));
    CHECK(2.0 * f.half_height_m == Approx(size.z()).epsilon(1e-6));
    CHECK(f.center_m.z() == Approx(0.5 * size.z()));
    walls_seen[std::size_t(owner)] |= 1 << (2 * axis + (f.normal[axis] > 0));
  }
  for (int seen : walls_seen) CHECK(seen == 0xF);
}

TEST_CASE("BuildWorldGeometry: poles and trees keep clear of intersections", "[core]") {
  WorldConfig c = GridConfig();
  bool expect_trees = true;
  SECTION("default streets") {}
  SECTION("narrow streets") { c.city.street_width_m = 4.0; }
  SECTION("small blocks, narrow streets: every tree slot is too close") {
    c.city.block_size_m = 10.0;
    c.city.street_width_m = 3.0;
    expect_trees = false;
  }
  const WorldGeometry w = Build(c, 5);
  const auto poles = MeshesNamed(w, "pole_");
  const auto trees = MeshesNamed(w, "tree_");
  REQUIRE(!poles.empty());
  CHECK(trees.empty() == !expect_trees);
  for (const auto* p : poles) {
    CHECK(p->material == kMaterialMetal);
    RequireClosedOutward(*p);
  }
  for (const auto* t : trees) {
    CHECK(t->material == kMaterialFoliage);
    RequireClosedOutward(*t);
  }
  const auto buildings = MeshesNamed(w, "building_");
  for (const auto& list : {poles, trees})
    for (const auto* m : list) {
      INFO(m->name);
      for (const auto& v : m->vertices_m) {
        CHECK(NearestIntersection_m(v.cast<double>(), c.city) >= 5.0 - 1e-4);
        // On a sidewalk: inside a block square, off the roadway.
        CHECK(BlockIndexOf(v.x(), c.city.blocks_x, c.city) >= 0);
        CHECK(BlockIndexOf(v.y(), c.city.blocks_y, c.city) >= 0);
      }
      // And clear of every building.
      const Box box = BoundsOf(*m);
      for (const auto* b : buildings) {
        const Box other = BoundsOf(*b);
        CHECK((box.hi.x() < other.lo.x() || other.hi.x() < box.lo.x() ||
               box.hi.y() < other.lo.y() || other.hi.y() < box.lo.y()));
      }
    }
}

TEST_CASE("BuildWorldGeometry: poles and trees can be turned off", "[core]") {
  WorldConfig c = GridConfig();
  c.city.poles = false;
  c.city.trees = false;
  const WorldGeometry w = Build(c);
  CHECK(MeshesNamed(w, "pole_").empty());
  CHECK(MeshesNamed(w, "tree_").empty());
  CHECK(w.meshes.size() == 1 + 8 * 4);
  // Street furniture draws from its own streams: the buildings stay put.
  const WorldGeometry full = Build(GridConfig());
  const auto a = MeshesNamed(w, "building_"), b = MeshesNamed(full, "building_");
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) CHECK(a[i]->vertices_m == b[i]->vertices_m);
}

const char* kUnitCubeObj = R"(# unit cube, faces counter-clockwise seen from outside
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
)";

WorldConfig MeshConfig(const std::string& path) {
  WorldConfig c;
  c.city.type = CityType::kMesh;
  c.city.path = path;
  c.city.scale = 2.0;
  c.city.offset_m = {10.0, -5.0, 1.0};
  return c;
}

TEST_CASE("BuildWorldGeometry: an OBJ or PLY unit cube is imported scaled and offset", "[core]") {
  const ScratchDir scratch;
  const std::string& dir = scratch.path;
  std::string file;
  SECTION("OBJ") {
    file = "cube.obj";
    scratch.Write(file, kUnitCubeObj);
  }
  SECTION("PLY") {
    file = "cube.ply";
    scratch.Write(file,
                  "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\n"
                  "property float y\nproperty float z\nelement face 6\n"
                  "property list uchar int vertex_indices\nend_header\n"
                  "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
                  "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n");
  }
  const WorldGeometry w = Build(MeshConfig(file), 1, dir);
  REQUIRE(w.meshes.size() == 2);
  CHECK(w.meshes[0].name == "ground");
  CHECK(w.facades.empty());
  const TriangleMesh& cube = w.meshes[1];
  CHECK(cube.triangles.size() == 12);
  CHECK(cube.material == kMaterialConcrete);
  RequireClosedOutward(cube);
  CHECK(SignedVolume(cube) == Approx(8.0));
  const Box b = BoundsOf(cube);
  CHECK(b.lo.isApprox(Vector3d(10.0, -5.0, 1.0)));
  CHECK(b.hi.isApprox(Vector3d(12.0, -3.0, 3.0)));
}

TEST_CASE("BuildWorldGeometry: OBJ material names map to built-in materials", "[core]") {
  const ScratchDir scratch;
  const std::string& dir = scratch.path;
  scratch.Write("m.obj",
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                "o a\nusemtl Facade_Glass\nf 1 2 3\n"
                "o b\nusemtl lamp_metal\nf 1 3 4\n"
                "o c\nusemtl TreeLeaves\nf 1 2 4\n"
                "o d\nusemtl brick\nf 2 3 4\n");
  const WorldGeometry w = Build(MeshConfig("m.obj"), 1, dir);
  std::map<std::string, std::uint32_t> material;
  for (const auto& m : w.meshes) material[m.name] = m.material;
  CHECK(material.at("a") == kMaterialGlass);
  CHECK(material.at("b") == kMaterialMetal);
  CHECK(material.at("c") == kMaterialFoliage);
  CHECK(material.at("d") == kMaterialConcrete);
}

TEST_CASE("BuildWorldGeometry: unreadable mesh files are ConfigErrors at /world/city/path",
          "[core]") {
  const ScratchDir scratch;
  const std::string& dir = scratch.path;
  std::string file, expected;
  SECTION("missing") {
    file = "no_such.obj";
    expected = "mesh file not found";
  }
  SECTION("empty") {
    file = "empty.obj";
    scratch.Write(file, "");
    expected = "cannot read the mesh";
  }
  SECTION("garbage PLY") {
    file = "bad.ply";
    scratch.Write(file, "not a ply file\n");
    expected = "cannot read the mesh";
  }
  SECTION("lines only") {
    file = "lines.obj";
    scratch.Write(file, "v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2 3\n");
    expected = "the mesh has no triangles";
  }
  try {
    Build(MeshConfig(file), 1, dir);
    FAIL("no ConfigError");
  } catch (const ConfigError& e) {
    CHECK(e.pointer() == "/world/city/path");
    CHECK(e.file() == dir + "/" + file);
    CHECK_THAT(e.message(), Catch::StartsWith(expected));
    CHECK_THAT(e.what(), Catch::Contains("/world/city/path: " + expected));
  }
}

TEST_CASE("MakeQuadrotorMesh: fills size_m, centred, closed, dark", "[core]") {
  Vector3d size(0.5, 0.5, 0.2);
  SECTION("default size") {}
  SECTION("oblong") { size = {0.9, 0.6, 0.3}; }
  const TriangleMesh m = MakeQuadrotorMesh(size);
  CHECK(m.material == kMaterialDrone);
  const Box b = BoundsOf(m);
  for (int i = 0; i < 3; ++i) {
    CHECK(b.lo[i] == Approx(-0.5 * size[i]).margin(1e-6));
    CHECK(b.hi[i] == Approx(0.5 * size[i]).margin(1e-6));
  }
  RequireClosedOutward(m);
  // Body, four arms, four rotor discs.
  CHECK(Components(m).size() == 9);
}

TEST_CASE("MakeBirdMesh: wingspan, centred, closed", "[core]") {
  const double span_m = 0.7;
  const TriangleMesh m = MakeBirdMesh(span_m);
  CHECK(m.material == kMaterialBird);
  const Box b = BoundsOf(m);
  CHECK(b.hi.y() - b.lo.y() == Approx(span_m).margin(1e-6));
  CHECK(b.Center().norm() < 1e-6);
  CHECK(b.Size().x() < span_m);
  RequireClosedOutward(m);
  CHECK(Components(m).size() == 3);  // body and two wings
}

}  // namespace
}  // namespace uavsim::core
