// What a run will cost before it starts: its wall time, from a model of
// this build's costs (the scenario's pixels, rays, radar cube samples,
// encoder passes and windows, each at its cost per core on the project's
// 2-core reference machine when idle: docs/speed.md "Wall-time model"),
// never from a timing taken now; and the bytes `--record` would write (upper
// estimates: a PNG or PLY at most its raw frame plus headers).
#pragma once

#include <string>
#include <vector>

#include "sim/scenario.h"

namespace uavsim::sim {

// Seconds of wall time the run would take on an idle machine of this core
// count, cores as fast as the reference machine's (its set-up included).
double EstimateWallSeconds(const Scenario& s);

// Bytes `uavsim run --record` of `modalities` ("camera", "lidar", "radar",
// "mcap") would write under DIR/frames and in DIR/recording.mcap, at most.
double EstimateRecordBytes(const Scenario& s, const std::vector<std::string>& modalities);

// Free bytes of the file system that holds `path` (or its nearest existing
// parent folder); -1 if unknown.
double FreeBytesFor(const std::string& path);

// A recording that would not fit out_dir's file system is refused before
// anything is made: core::UsageError "COMMAND: --record would write ...".
void RequireRoomToRecord(const Scenario& s, const std::vector<std::string>& record,
                         const std::string& out_dir, const std::string& command);

}  // namespace uavsim::sim
