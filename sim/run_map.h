// What a run's report draws its top view from (DESIGN.md results/: plots read
// only the run's CSVs), written beside truth.csv:
//
//  world_top.csv  x_m,y_m,height_m,surface: the static world seen from above
//                 on a square grid of cell_m cells (cell centres), one row
//                 per cell whose top surface is not bare ground (height above
//                 0.25 m or a material other than the ground's); surface is
//                 the material's name (concrete, glass, metal, foliage, or a
//                 mesh's). The grid covers the run's area of interest: the
//                 nodes, the base station and the target's path, with a
//                 margin of 60 % or 30 m; cell_m is the smallest of 0.5, 1, 2, 4, 5, 10 m ...
//                 giving at most 200 cells across.
//  layout.csv     object,kind,x_m,y_m,z_m: a row per node (kind camera,
//                 lidar or radar) and one for the base station (object and
//                 kind base_station), each at its position; then per node
//                 its horizontal field of view as a closed polygon (kind
//                 fov, the node's rows in order, last = first): the
//                 boresight's azimuth +- the half field of view across the
//                 image or scan (a full circle for a spinning LiDAR), out to
//                 the farthest the target comes from the node (x 1.15), or
//                 the sensor's range if shorter.
//
// Numbers have 3 decimals (height_m 2). Deterministic: the scene's static
// part and the target's closed-form path only, no randomness.
#pragma once

#include "results/csv.h"
#include "sim/scenario.h"
#include "sim/world_model.h"

namespace uavsim::sim {

results::CsvTable WorldTopTable(const Scenario& scenario, const WorldModel& world);
results::CsvTable LayoutTable(const Scenario& scenario, const WorldModel& world);

}  // namespace uavsim::sim
