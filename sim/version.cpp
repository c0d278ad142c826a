#include "sim/version.h"

namespace uavsim::sim {
const char* Version() { return UAVSIM_VERSION; }
const char* GitHash() { return UAVSIM_GIT_HASH; }
}  // namespace uavsim::sim
