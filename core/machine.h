// What the machine has, for the resource guard.
#pragma once

namespace uavsim::core {

// Physical memory in bytes (sysconf), or 0 when the system does not say.
double PhysicalMemoryBytes();

}  // namespace uavsim::core
