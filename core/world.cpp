#include "core/world.h"

#include "core/json_io.h"

namespace uavsim::core {

template <class V>
void Visit(V& v, CityConfig& c) {
  v.Enum("type", c.type,
         {{"open", CityType::kOpen}, {"grid", CityType::kGrid}, {"mesh", CityType::kMesh}});
  switch (c.type) {
    case CityType::kOpen:
      break;
    case CityType::kGrid:
      v("blocks_x", c.blocks_x, Rule::Range(1, 64));
      v("blocks_y", c.blocks_y, Rule::Range(1, 64));
      v("block_size_m", c.block_size_m, Rule::Range(5.0, 1000.0));
      v("street_width_m", c.street_width_m, Rule::Range(2.0, 500.0));
      v("buildings_per_block", c.buildings_per_block, Rule::Range(1, 64));
      v("min_height_m", c.min_height_m, Rule::Range(1.0, 1000.0));
      v("max_height_m", c.max_height_m, Rule::Range(1.0, 1000.0));
      v.Check(c.min_height_m <= c.max_height_m, "max_height_m",
              "max_height_m must be >= min_height_m (" + FormatNumber(c.min_height_m) + ")");
      v("central_plaza", c.central_plaza);
      v("poles", c.poles);
      v("trees", c.trees);
      break;
    case CityType::kMesh:
      v("path", c.path);
      v.Check(!c.path.empty(), "path", "expected the path of an OBJ or PLY file");
      v("scale", c.scale, Rule::Positive(1e6));
      v("offset_m", c.offset_m, Rule::Range(-1e6, 1e6));
      break;
  }
}
UAVSIM_INSTANTIATE_VISIT(CityConfig);

template <class V>
void Visit(V& v, WorldConfig& c) {
  v.Object("city", c.city);
  v("ground_size_m", c.ground_size_m, Rule::Range(10.0, 1e5));
}
UAVSIM_INSTANTIATE_VISIT(WorldConfig);

}  // namespace uavsim::core
