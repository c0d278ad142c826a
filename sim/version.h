// The build's version and git hash (empty when built outside a git checkout).
#pragma once

namespace uavsim::sim {
const char* Version();
const char* GitHash();
}  // namespace uavsim::sim
