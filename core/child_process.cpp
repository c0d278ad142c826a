#include "core/child_process.h"

#include <signal.h>
#include <sys/prctl.h>
#include <unistd.h>

namespace uavsim::core {

void DieWithParent(pid_t parent) noexcept {
  // If the parent ended before prctl, the child was already re-parented
  // (to init or a subreaper) and no signal will come: look.
  if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) ::_exit(128 + SIGKILL);
}

}  // namespace uavsim::core
