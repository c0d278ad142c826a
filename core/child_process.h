// Child processes that never outlive the process that started them. A
// command's visible PID (what a shell's `kill %1`, a scheduler or Python's
// subprocess.kill() signals) is the only one its user knows: killed by any
// signal, even SIGKILL, which no handler sees, every process doing its work
// must stop with it, and nothing may write into its output afterwards.
// Linux's parent-death signal does that: each child asks the kernel for
// SIGKILL when the thread that forked it ends (the fork's caller waits for
// its children on that same thread, so that is when the process ends), and
// the grandchildren it forks in turn do the same, so a whole tree of
// processes goes down with its root.
#pragma once

#include <sys/types.h>

namespace uavsim::core {

// In a child just forked by process `parent` (its getpid() before the
// fork): asks for SIGKILL when the parent ends, and ends at once (_exit
// 137) if the parent has already ended between the fork and this call.
// Async-signal-safe (it makes two system calls), so it may run between
// fork and exec.
void DieWithParent(pid_t parent) noexcept;

}  // namespace uavsim::core
