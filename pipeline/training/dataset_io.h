// Training episodes on disk (`uavsim train --data FILE`): simulate once, train
// many times. A versioned little-endian binary file; camera crops are stored
// as the 8-bit grey values they were made from (lossless).
#pragma once

#include <string>
#include <vector>

#include "pipeline/training/dataset.h"

namespace uavsim::pipeline {

// Writes atomically (temp file, then rename). Throws std::runtime_error
// naming the path.
void WriteEpisodes(const std::vector<Episode>& episodes, const std::string& path);
// Throws std::runtime_error naming the path for a missing, truncated or
// foreign file.
std::vector<Episode> ReadEpisodes(const std::string& path);

}  // namespace uavsim::pipeline
