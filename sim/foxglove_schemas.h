// The JSON schemas of the Foxglove message types a recording uses (schema
// encoding "jsonschema", message encoding "json"), written here from the
// Foxglove schema definitions: the same titles, properties, types, enums
// and required fields (descriptions left out), bytes fields as base64
// strings ("contentEncoding": "base64"), times as {sec, nsec}. The MCAP
// reader test compares each with the @foxglove/schemas package's, so a
// drift fails there. Plus the run's own JSON types ("uavsim.*").
#pragma once

#include <string>

#include "core/json_io.h"

namespace uavsim::sim {

// The schema of `name`: "foxglove.SceneUpdate", "foxglove.FrameTransform",
// "foxglove.CompressedImage", "foxglove.CameraCalibration",
// "foxglove.PointCloud", "uavsim.WindowError" or "uavsim.UplinkMessage".
// Throws std::invalid_argument for any other name.
core::Json FoxgloveSchema(const std::string& name);

}  // namespace uavsim::sim
