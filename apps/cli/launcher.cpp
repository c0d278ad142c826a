// The `uavsim` command as it is started: it blocks SIGINT and SIGTERM, then
// runs the command line, `uavsim-light` beside it, in its place (the same
// process, arguments and environment), which runs uavsim-main in its place
// in turn for a command that needs LibTorch (apps/cli/cli.h). Loading a
// program takes the dynamic loader a while (uavsim-main's LibTorch
// relocations: 0.1 s on an idle machine, 0.8 s on a loaded one), before any
// of its code can install a handler; a signal in that time would end it by
// the default action (exit 143, no message). Blocked, the signal waits, and
// the program answers it as documented once its handlers are in
// (apps/cli/light_main.cpp, main.cpp). This file uses the C library only, so
// that its own start costs next to nothing.
#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

int main(int, char** argv) {
  sigset_t termination;
  sigemptyset(&termination);
  sigaddset(&termination, SIGINT);
  sigaddset(&termination, SIGTERM);
  sigprocmask(SIG_BLOCK, &termination, nullptr);
  static const char kSuffix[] = "-light";
  char path[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", path, sizeof path - sizeof kSuffix);
  if (n <= 0) {
    fprintf(stderr, "uavsim: cannot find its own executable: %s\n", strerror(errno));
    return 1;
  }
  memcpy(path + n, kSuffix, sizeof kSuffix);
  execv(path, argv);
  fprintf(stderr, "uavsim: cannot run %s: %s\n", path, strerror(errno));
  return 1;
}
