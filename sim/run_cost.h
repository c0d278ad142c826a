// What a run will cost before it starts (issue 43): its wall time on this
// machine, estimated from the rays and the frames per simulated second, and
// the bytes `--record` would write. Upper estimates for the disk (a PNG or
// PLY at most its raw frame plus headers); the wall time from per-ray and
// per-frame costs measured on the project's 2-core reference machine under
// load (an upper estimate on an idle one; the figures are in NOTES.md), scaled by
// this machine's core count.
#pragma once

#include <string>
#include <vector>

#include "sim/scenario.h"

namespace uavsim::sim {

// Seconds of wall time the run would take here (its set-up included).
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
