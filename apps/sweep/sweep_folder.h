// A sweep's folder as files (DIR/sweep.json, DIR/points/ID/) and its tables
// and report made from them: what `uavsim sweep` writes once every point
// is done and `uavsim report DIR` redraws. Runs nothing, so it needs no
// LibTorch (apps/cli's light program links it).
#pragma once

#include <string>

#include "apps/sweep/sweep.h"
#include "apps/sweep/sweep_spec.h"
#include "core/json_io.h"

namespace uavsim::sim {

// sweep.json's "format".
inline constexpr const char* kSweepFormat = "uavsim-sweep/1";

// DIR/sweep.json: the expanded grid, what tables and plots need.
core::Json SweepRecord(const SweepSpec& spec);

// DIR/points/ID, and whether that point is finished (its metrics.json).
std::string PointDir(const std::string& dir, const std::string& id);
bool PointDone(const std::string& dir, const std::string& id);

}  // namespace uavsim::sim
