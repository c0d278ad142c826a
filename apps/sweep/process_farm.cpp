#include "apps/sweep/process_farm.h"

#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <tbb/global_control.h>
#include <boost/mpi/communicator.hpp>
#include <boost/serialization/string.hpp>
#include <boost/serialization/utility.hpp>
#include <boost/serialization/vector.hpp>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/atomic_file.h"
#include "core/child_process.h"
#include "core/progress.h"
#include "sim/run.h"

namespace uavsim::sim {
namespace {

namespace fs = std::filesystem;

// Cores this process may run on.
int CoresAvailable() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

// How many ranks of this job share this host.
int LocalRanks() {
  for (const char* v : {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS", "PMI_LOCAL_SIZE"})
    if (const char* s = std::getenv(v)) return std::max(1, std::atoi(s));
  return 1;
}

int ThreadsPerTask(int jobs) { return std::max(1, CoresAvailable() / (LocalRanks() * jobs)); }

// A task runs in a child process (fork, no exec): the child has everything
// the task needs in memory, runs it with `threads` cores for TBB's pool
// (LibTorch runs on one thread in every run), and exits.
pid_t LaunchTask(const ProcessFarm& farm, std::size_t task, const std::string& dir, int threads) {
  std::fflush(nullptr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0)
    throw std::runtime_error(farm.command + ": cannot start a task: fork: " + std::strerror(errno));
  if (pid > 0) return pid;
  core::DieWithParent(parent);  // a killed command takes its tasks with it
  int rc = 0;
  try {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));
    farm.run(task, dir);
  } catch (const core::Interrupted&) {
    rc = 130;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s: %s\n", farm.command.c_str(), farm.describe(task).c_str(),
                 e.what());
    rc = 1;
  }
  std::fflush(nullptr);
  ::_exit(rc);
}

// Tasks not yet started, in order, and those not yet ended: a task is
// ready when the task it comes after (ProcessFarm::after) has ended.
class TaskQueue {
 public:
  TaskQueue(const ProcessFarm& farm, std::deque<std::size_t> tasks)
      : farm_(farm), waiting_(std::move(tasks)), unended_(waiting_.begin(), waiting_.end()) {}
  bool empty() const { return waiting_.empty(); }
  std::size_t size() const { return waiting_.size(); }
  // The first ready task, taken out of the queue (it stays unended).
  std::optional<std::size_t> PopReady() {
    for (auto it = waiting_.begin(); it != waiting_.end(); ++it) {
      const std::optional<std::size_t> first = farm_.after ? farm_.after(*it) : std::nullopt;
      if (first && *first != *it && unended_.count(*first)) continue;
      const std::size_t task = *it;
      waiting_.erase(it);
      return task;
    }
    return std::nullopt;
  }
  void Ended(std::size_t task) { unended_.erase(task); }

 private:
  const ProcessFarm& farm_;
  std::deque<std::size_t> waiting_;
  std::set<std::size_t> unended_;
};

// Children of this process, task by pid.
class ChildPool {
 public:
  ChildPool(const ProcessFarm& farm, int slots)
      : farm_(farm), slots_(slots), threads_(ThreadsPerTask(slots)) {}
  ~ChildPool() { KillAll(); }
  bool HasSlot() const { return static_cast<int>(running_.size()) < slots_; }
  bool empty() const { return running_.empty(); }
  void Launch(std::size_t task, const std::string& dir) {
    running_[LaunchTask(farm_, task, dir, threads_)] = task;
  }
  // Starts the first ready tasks of `queue` into their local folders while
  // there are free slots. Returns whether it started any.
  bool Fill(TaskQueue& queue) {
    bool started = false;
    while (HasSlot()) {
      const std::optional<std::size_t> task = queue.PopReady();
      if (!task) break;
      Launch(*task, farm_.local_dir(*task));
      started = true;
    }
    return started;
  }
  // A finished child: (task, exit code), without blocking.
  std::optional<std::pair<std::size_t, int>> Reap() {
    for (auto it = running_.begin(); it != running_.end(); ++it) {
      int status = 0;
      const pid_t r = ::waitpid(it->first, &status, WNOHANG);
      if (r == 0) continue;
      const std::size_t task = it->second;
      running_.erase(it);
      const int rc = r < 0 ? 1 : WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return std::make_pair(task, rc);
    }
    return std::nullopt;
  }
  // Asks every child to stop (they discard their staging folders) and waits.
  void KillAll() {
    for (const auto& [pid, task] : running_) ::kill(pid, SIGTERM);
    for (const auto& [pid, task] : running_) {
      int status = 0;
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
    }
    running_.clear();
  }
  // Stops everything if a termination signal arrived.
  void ThrowIfInterrupted() {
    if (!core::InterruptRequested()) return;
    KillAll();
    throw core::Interrupted();
  }

 private:
  const ProcessFarm& farm_;
  int slots_, threads_;
  std::map<pid_t, std::size_t> running_;
};

void Nap() { std::this_thread::sleep_for(std::chrono::milliseconds(10)); }

// Boost.MPI messages:
//   worker -> 0  kRequest  (nothing)        a free slot
//   0 -> worker  kAssign   task index, or -1: no more tasks
//   worker -> 0  kResult   TaskResult       a task's outcome and files
enum Tag { kRequest = 1, kAssign = 2, kResult = 3 };

struct TaskResult {
  long long task = -1;
  int rc = 0;
  TaskFiles files;

  template <class Archive>
  void serialize(Archive& ar, unsigned) {
    ar& task& rc& files;
  }
};

}  // namespace

TaskFiles ReadTree(const std::string& root) {
  TaskFiles files;
  for (const auto& e : fs::recursive_directory_iterator(root))
    if (e.is_regular_file())
      files.emplace_back(fs::relative(e.path(), root).string(),
                         core::ReadFileBytes(e.path().string()));
  std::sort(files.begin(), files.end());
  return files;
}

bool UnderMpirun() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(v)) return true;
  return false;
}

FarmCounts RunFarmLocal(const ProcessFarm& farm, std::deque<std::size_t> tasks,
                        const FarmOptions& o) {
  core::Progress progress(o.label, static_cast<double>(tasks.size()), farm.unit, o.quiet);
  TaskQueue queue(farm, std::move(tasks));
  ChildPool pool(farm, o.jobs);
  FarmCounts counts;
  while (!queue.empty() || !pool.empty()) {
    pool.ThrowIfInterrupted();
    bool busy = pool.Fill(queue);
    while (const auto done = pool.Reap()) {
      busy = true;
      if (done->second == 130) {
        pool.KillAll();
        throw core::Interrupted();
      }
      queue.Ended(done->first);
      done->second == 0 ? ++counts.ran : ++counts.failed;
      progress.Update(static_cast<double>(counts.ran + counts.failed));
      if (farm.ended) farm.ended(done->first, done->second);
    }
    if (!busy) Nap();
  }
  progress.Finish();
  return counts;
}

FarmCounts RunFarmCoordinator(boost::mpi::communicator& world, const ProcessFarm& farm,
                              std::deque<std::size_t> tasks, const FarmOptions& o) {
  core::Progress progress(o.label + " (" + std::to_string(world.size()) + " ranks)",
                          static_cast<double>(tasks.size()), farm.unit, o.quiet);
  TaskQueue queue(farm, std::move(tasks));
  ChildPool pool(farm, o.jobs);
  FarmCounts counts;
  int workers = world.size() - 1;  // not yet told to stop
  std::size_t remote = 0;
  std::deque<int> asking;  // workers with a free slot and no answer yet
  const auto count = [&](std::size_t task, int rc) {
    queue.Ended(task);
    rc == 0 ? ++counts.ran : ++counts.failed;
    progress.Update(static_cast<double>(counts.ran + counts.failed));
    if (farm.ended) farm.ended(task, rc);
  };
  while (!queue.empty() || !pool.empty() || workers > 0 || remote > 0) {
    pool.ThrowIfInterrupted();
    bool busy = false;
    while (auto st = world.iprobe(boost::mpi::any_source, kRequest)) {
      world.recv(st->source(), kRequest);
      asking.push_back(st->source());
      busy = true;
    }
    // A worker gets a ready task, or is told to stop when none is left; it
    // waits while the tasks left wait for others to end.
    while (!asking.empty()) {
      long long assign = -1;
      if (const std::optional<std::size_t> task = queue.PopReady()) {
        assign = static_cast<long long>(*task);
        ++remote;
      } else if (!queue.empty()) {
        break;
      } else {
        --workers;
      }
      world.send(asking.front(), kAssign, assign);
      asking.pop_front();
      busy = true;
    }
    while (auto st = world.iprobe(boost::mpi::any_source, kResult)) {
      TaskResult r;
      world.recv(st->source(), kResult, r);
      --remote;
      if (r.rc == 0) farm.commit_remote(static_cast<std::size_t>(r.task), r.files);
      count(static_cast<std::size_t>(r.task), r.rc);
      busy = true;
    }
    // Rank 0's own slots; a task is handed to a worker first when both wait.
    busy = pool.Fill(queue) || busy;
    while (const auto done = pool.Reap()) {
      count(done->first, done->second);
      busy = true;
    }
    if (!busy) Nap();
  }
  progress.Finish();
  return counts;
}

FarmCounts RunFarmWorker(boost::mpi::communicator& world, const ProcessFarm& farm,
                         const FarmOptions& o) {
  char tmpl[] = "/tmp/uavsim-farm-rank-XXXXXX";
  if (!::mkdtemp(tmpl)) throw std::runtime_error("cannot create a temporary folder in /tmp");
  const fs::path scratch(tmpl);
  struct Cleanup {
    fs::path p;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(p, ec);
    }
  } cleanup{scratch};
  const auto task_dir = [&](std::size_t task) { return scratch / std::to_string(task); };
  ChildPool pool(farm, o.jobs);
  FarmCounts counts;
  bool asked = false, stopped = false;
  while (!stopped || !pool.empty()) {
    pool.ThrowIfInterrupted();
    bool busy = false;
    if (!stopped && !asked && pool.HasSlot()) {
      world.send(0, kRequest);
      asked = true;
    }
    if (asked && world.iprobe(0, kAssign)) {
      long long i = -1;
      world.recv(0, kAssign, i);
      asked = false;
      busy = true;
      if (i < 0)
        stopped = true;
      else
        pool.Launch(static_cast<std::size_t>(i), task_dir(static_cast<std::size_t>(i)).string());
    }
    while (const auto done = pool.Reap()) {
      TaskResult r;
      r.task = static_cast<long long>(done->first);
      r.rc = done->second;
      const fs::path dir = task_dir(done->first);
      if (r.rc == 0) r.files = ReadTree(dir.string());
      std::error_code ec;
      fs::remove_all(dir, ec);
      world.send(0, kResult, r);
      r.rc == 0 ? ++counts.ran : ++counts.failed;
      busy = true;
    }
    if (!busy) Nap();
  }
  return counts;
}

}  // namespace uavsim::sim
