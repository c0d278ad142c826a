#include "core/machine.h"

#include <unistd.h>

namespace uavsim::core {

double PhysicalMemoryBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page_bytes = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page_bytes <= 0) return 0.0;
  return static_cast<double>(pages) * static_cast<double>(page_bytes);
}

}  // namespace uavsim::core
