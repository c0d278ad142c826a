// Independent tasks 0..n-1 run in child processes (fork, no exec): a crash
// or a kill costs one task, and each task gets its own cores. A task's
// process dies with the farm's (core/child_process.h): a command killed by
// any signal, SIGKILL included, leaves no task running or writing. Sweeps run
// their points this way, training its episodes.
//
//  - on one machine: `jobs` tasks at a time; a terminal shows tasks done,
//    rate and ETA.
//  - under mpirun: rank 0 hands out tasks one at a time to whichever rank
//    asks (slow tasks do not stall the rest) and runs tasks itself; other
//    ranks run theirs in a private temporary folder and send the files
//    back, so only rank 0 writes (no shared file system needed).
//
// A task writes files into the folder it is given; what it writes, and in
// which order tasks finish, is the caller's business: a caller that needs
// the same output whatever `jobs` or the ranks reads the tasks' files back
// in task order.
#pragma once

#include <cstddef>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace boost::mpi {
class communicator;
}

namespace uavsim::sim {

// A task's files: path relative to its folder -> bytes.
using TaskFiles = std::vector<std::pair<std::string, std::string>>;

struct ProcessFarm {
  std::string command;  // for messages: "uavsim sweep"
  std::string unit;     // what a task is, for progress: "points", "episodes"
  // In the child: runs task i, writing into `dir` (which it creates). Throws
  // Interrupted on a termination signal, anything else on failure.
  std::function<void(std::size_t task, const std::string& dir)> run;
  // For messages: "point lw-3".
  std::function<std::string(std::size_t task)> describe;
  // At rank 0: the folder a task rank 0 runs writes into.
  std::function<std::string(std::size_t task)> local_dir;
  // At rank 0: a task another rank ran succeeded; write its files.
  std::function<void(std::size_t task, const TaskFiles& files)> commit_remote;
  // Optional: the task that must have ended (succeeded or failed) before
  // `task` starts, if it is among the tasks run; nullopt: none. (A sweep's
  // points that replay a sensing trace wait for the point that writes it.)
  std::function<std::optional<std::size_t>(std::size_t task)> after;
  // Optional: at rank 0, once task `task` has ended with exit code `rc` (0:
  // succeeded) and its files are in place.
  std::function<void(std::size_t task, int rc)> ended;
};

struct FarmOptions {
  int jobs = 1;  // tasks at a time on this process (each rank under MPI)
  bool quiet = false;
  std::string label;  // progress line: "sweep loss_weather"
};

struct FarmCounts {
  std::size_t ran = 0;     // succeeded
  std::size_t failed = 0;  // exited non-zero (their message is on stderr)
};

// Runs `queue` here, `jobs` at a time. Throws Interrupted (after stopping
// the children) when a termination signal arrives.
FarmCounts RunFarmLocal(const ProcessFarm& farm, std::deque<std::size_t> queue,
                        const FarmOptions& o);
// Rank 0 under MPI: hands out `queue` to every rank (itself included) and
// commits what the others send; returns when all are done.
FarmCounts RunFarmCoordinator(boost::mpi::communicator& world, const ProcessFarm& farm,
                              std::deque<std::size_t> queue, const FarmOptions& o);
// Any other rank: asks rank 0 for tasks until it says there are none.
FarmCounts RunFarmWorker(boost::mpi::communicator& world, const ProcessFarm& farm,
                         const FarmOptions& o);

// Whether this process was started by mpirun/mpiexec (OpenMPI, PMI, PMIx).
bool UnderMpirun();

// Reads a whole folder: its regular files, relative path -> bytes, sorted.
TaskFiles ReadTree(const std::string& root);

}  // namespace uavsim::sim
