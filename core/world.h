// The static world as plain data: a procedural city, an open field, or a
// user's mesh. The Embree scene built from it lives in sensors/.
#pragma once

#include <Eigen/Core>
#include <string>

namespace uavsim::core {

enum class CityType { kOpen, kGrid, kMesh };

struct CityConfig {
  CityType type = CityType::kGrid;
  // grid: blocks_x by blocks_y blocks of block_size_m, separated by streets,
  // centred on the origin; building heights and footprints drawn from the
  // world's RNG stream.
  int blocks_x = 3;
  int blocks_y = 3;
  double block_size_m = 40.0;
  double street_width_m = 20.0;
  int buildings_per_block = 4;
  double min_height_m = 8.0;
  double max_height_m = 30.0;
  bool central_plaza = true;  // leave the centre block open (where the default UAV flies)
  bool poles = true;
  bool trees = true;
  // mesh: OBJ or PLY path, relative to the scenario file's folder.
  std::string path;
  double scale = 1.0;
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
};

struct WorldConfig {
  CityConfig city;
  double ground_size_m = 400.0;  // square ground plane side, centred on the origin
};

template <class V>
void Visit(V& v, CityConfig& c);
template <class V>
void Visit(V& v, WorldConfig& c);

}  // namespace uavsim::core
