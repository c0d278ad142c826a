#include "apps/sweep/sweep.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <boost/mpi/communicator.hpp>
#include <boost/mpi/environment.hpp>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>

#include "apps/sweep/process_farm.h"
#include "apps/sweep/recorded_folder.h"
#include "apps/sweep/sweep_folder.h"
#include "core/error.h"
#include "core/file_lock.h"
#include "core/progress.h"
#include "results/run_directory.h"
#include "sim/edge_server.h"
#include "sim/run.h"
#include "sim/sensing_trace.h"

namespace uavsim::sim {
namespace {

namespace fs = std::filesystem;
using core::Json;

// Creates DIR (and DIR/points) for `record`, or checks that an existing DIR
// holds the same sweep.
void PrepareDir(const std::string& dir, const Json& record) {
  results::RemoveStaleStaging(dir);  // what killed commands left beside it, of any name
  if (const std::optional<Json> old = ReadFolderRecord(dir, "sweep.json")) {
    if (*old != record)
      throw core::UsageError(dir +
                             ": holds another sweep (its spec, base scenario or grid differ); "
                             "choose another --out or remove it");
    return;
  }
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_empty(dir, ec))
    throw core::UsageError(dir + ": exists and is not a sweep; choose another --out");
  CreateRecordedFolder(dir, "sweep.json", record, {"points"});
}

// The lock of a sweep's folder, a shard's own (the shards of one grid run
// side by side: their points differ).
std::string LockPath(const SweepOptions& o) {
  const std::string name = o.shard_count == 1 ? ".lock"
                                              : ".lock-shard-" + std::to_string(o.shard_index) +
                                                    "-of-" + std::to_string(o.shard_count);
  return (fs::path(o.out_dir) / name).string();
}

// Removes the staging folders ".ID.partial-PID" of points killed mid-way
// (those whose process is gone), among the points this invocation runs:
// another shard's points may be in the making on another host.
void RemoveStalePartials(const std::string& dir, const std::set<std::string>& ours) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "points", ec)) {
    std::string id;
    const auto pid = results::StagingOwner(e.path().filename().string(), &id);
    if (!pid || !ours.count(id) || results::ProcessAlive(*pid)) continue;
    std::error_code rm;
    fs::remove_all(e.path(), rm);
  }
}

// Points this invocation should run: its shard, not yet done.
std::deque<std::size_t> PointsToRun(const SweepSpec& spec, const SweepOptions& o,
                                    SweepOutcome& out) {
  std::deque<std::size_t> queue;
  for (std::size_t i = 0; i < spec.points.size(); ++i) {
    if (PointDone(o.out_dir, spec.points[i].id)) {
      ++out.already_done;
      continue;
    }
    if (static_cast<int>(i % static_cast<std::size_t>(o.shard_count)) == o.shard_index)
      queue.push_back(i);
  }
  return queue;
}

// The ids of this invocation's shard.
std::set<std::string> ShardIds(const SweepSpec& spec, const SweepOptions& o) {
  std::set<std::string> ids;
  for (std::size_t i = 0; i < spec.points.size(); ++i)
    if (static_cast<int>(i % static_cast<std::size_t>(o.shard_count)) == o.shard_index)
      ids.insert(spec.points[i].id);
  return ids;
}

// Rank 0 writes a worker's point all-or-nothing, as a run would.
void CommitPoint(const std::string& dir, const std::string& id, const TaskFiles& files) {
  results::RunDirectory run(PointDir(dir, id), false);
  for (const auto& [path, bytes] : files) run.WriteText(path, bytes);
  run.Commit();
}

// Which points sense once for the others (SweepOptions::traces): each
// point's sensing key, the point that writes a group's trace, and the one
// each point waits for.
struct TracePlan {
  std::string dir;           // absolute DIR/traces; empty: every point senses
  std::string sweep_record;  // absolute DIR/sweep.json: whether DIR is on this host
  std::vector<std::string> key;
  std::vector<bool> writes;
  std::vector<std::optional<std::size_t>> after;
};

// The sensing key of every point (the model's fingerprint once per model);
// empty for a point whose model does not resolve: it senses by itself and
// fails as it runs, costing that point only.
std::vector<std::string> SensingKeys(const SweepSpec& spec) {
  std::map<std::string, std::string> fingerprints;  // pipeline as JSON -> fingerprint
  std::vector<std::string> keys;
  for (std::size_t i = 0; i < spec.points.size(); ++i) {
    const Scenario s = spec.PointScenario(i);
    const std::string pipeline = ResolvedJson(s).at("pipeline").dump() + "@" + s.base_dir;
    auto it = fingerprints.find(pipeline);
    if (it == fingerprints.end()) {
      std::string fingerprint;
      try {
        fingerprint = EncoderFingerprint(s, spec.file);
      } catch (const std::exception&) {
        // left empty: no key
      }
      it = fingerprints.emplace(pipeline, fingerprint).first;
    }
    std::string key;
    try {
      if (!it->second.empty()) key = SensingKey(s, it->second);
    } catch (const std::exception&) {
      // an unreadable city mesh: no key either
    }
    keys.push_back(key);
  }
  return keys;
}

// Among the points to run, the first of each key whose trace is missing
// writes it when others share the key; they wait for it.
TracePlan PlanTraces(const SweepSpec& spec, const SweepOptions& o,
                     const std::deque<std::size_t>& queue) {
  TracePlan plan;
  const std::size_t n = spec.points.size();
  plan.writes.assign(n, false);
  plan.after.assign(n, std::nullopt);
  if (!o.traces) return plan;
  plan.dir = fs::absolute(fs::path(o.out_dir) / "traces").lexically_normal().string();
  plan.sweep_record = fs::absolute(fs::path(o.out_dir) / "sweep.json").string();
  plan.key = SensingKeys(spec);
  std::map<std::string, std::vector<std::size_t>> groups;
  for (std::size_t i : queue)
    if (!plan.key[i].empty()) groups[plan.key[i]].push_back(i);
  for (const auto& [key, points] : groups) {
    std::error_code ec;
    if (points.size() < 2 || fs::exists(SensingTracePath(plan.dir, key), ec)) continue;
    plan.writes[points.front()] = true;
    for (std::size_t j = 1; j < points.size(); ++j) plan.after[points[j]] = points.front();
  }
  return plan;
}

// Leaders first, so that the points waiting for them start as early as can be.
std::deque<std::size_t> LeadersFirst(std::deque<std::size_t> queue, const TracePlan& plan) {
  std::stable_partition(queue.begin(), queue.end(), [&](std::size_t i) { return plan.writes[i]; });
  return queue;
}

// Where point i's run traces or replays: replays a trace that exists, writes
// one if it leads its group; neither when DIR is not on this host.
void WireTraces(const TracePlan& plan, std::size_t i, RunOptions& o) {
  std::error_code ec;
  if (plan.dir.empty() || plan.key[i].empty() || !fs::is_regular_file(plan.sweep_record, ec))
    return;
  if (fs::is_regular_file(SensingTracePath(plan.dir, plan.key[i]), ec))
    o.replay_dir = plan.dir;
  else if (plan.writes[i])
    o.trace_dir = plan.dir;
}

// Each point is a whole run directory: DIR/points/<id> when rank 0 runs it.
ProcessFarm PointFarm(const SweepSpec& spec, const std::string& dir, const TracePlan& plan) {
  ProcessFarm farm;
  farm.command = "uavsim sweep";
  farm.unit = "points";
  farm.run = [&spec, &plan](std::size_t i, const std::string& run_dir) {
    RunOptions o;
    o.out_dir = run_dir;
    o.quiet = true;
    o.report = false;  // the sweep's report is the product; a point's is drawn on demand
    o.scenario_file = spec.file + "#" + spec.points[i].id;
    WireTraces(plan, i, o);
    RunScenario(spec.PointScenario(i), o);
  };
  farm.after = [&plan](std::size_t i) { return plan.after[i]; };
  farm.describe = [&spec](std::size_t i) { return "point " + spec.points[i].id; };
  farm.local_dir = [&spec, dir](std::size_t i) { return PointDir(dir, spec.points[i].id); };
  farm.commit_remote = [&spec, dir](std::size_t i, const TaskFiles& files) {
    CommitPoint(dir, spec.points[i].id, files);
  };
  return farm;
}

}  // namespace

SweepOutcome RunSweep(const SweepSpec& spec, const SweepOptions& o) {
  if (o.jobs < 1) throw core::UsageError("uavsim sweep: --jobs needs at least 1");
  if (o.shard_count < 1 || o.shard_index < 0 || o.shard_index >= o.shard_count)
    throw core::UsageError("uavsim sweep: --shard I/N needs 0 <= I < N");
  SweepOutcome out;
  out.points = spec.points.size();
  const Json record = SweepRecord(spec);

  std::unique_ptr<boost::mpi::environment> env;
  std::unique_ptr<boost::mpi::communicator> world;
  if (UnderMpirun()) {
    env = std::make_unique<boost::mpi::environment>();
    world = std::make_unique<boost::mpi::communicator>();
    out.ranks = world->size();
  }
  const bool coordinator = !world || world->rank() == 0;
  TracePlan plan;  // every rank plans alike (rank 0's plan is the one that counts)
  ProcessFarm farm = PointFarm(spec, o.out_dir, plan);
  FarmOptions fo;
  fo.jobs = o.jobs;
  fo.quiet = o.quiet;
  fo.label = "sweep " + spec.name;
  const auto add = [&out](const FarmCounts& c) {
    out.ran += c.ran;
    out.failed += c.failed;
  };
  std::optional<core::FileLock> lock;  // held to the end, the merge included
  try {
    if (!coordinator) {
      out.mpi_worker = true;
      world->barrier();  // rank 0 has prepared DIR
      plan = PlanTraces(spec, o, PointsToRun(spec, o, out));
      out.already_done = 0;
      add(RunFarmWorker(*world, farm, fo));
      return out;
    }
    std::deque<std::size_t> queue;
    if (world) {
      // Rank 0 prepares DIR; the others wait, and learn whether it could.
      int ok = 0;
      std::string error;
      try {
        PrepareDir(o.out_dir, record);
        lock.emplace(LockPath(o), "uavsim sweep: " + o.out_dir, o.wait);
        RemoveStalePartials(o.out_dir, ShardIds(spec, o));
        queue = PointsToRun(spec, o, out);
        plan = PlanTraces(spec, o, queue);
        queue = LeadersFirst(std::move(queue), plan);
        ok = 1;
      } catch (const std::exception& e) {
        error = e.what();
      }
      if (!ok) {
        std::cerr << error << "\n";
        world->abort(2);
      }
      world->barrier();
      add(RunFarmCoordinator(*world, farm, std::move(queue), fo));
    } else {
      PrepareDir(o.out_dir, record);
      lock.emplace(LockPath(o), "uavsim sweep: " + o.out_dir, o.wait);
      RemoveStalePartials(o.out_dir, ShardIds(spec, o));
      queue = PointsToRun(spec, o, out);
      plan = PlanTraces(spec, o, queue);
      queue = LeadersFirst(std::move(queue), plan);
      add(RunFarmLocal(farm, std::move(queue), fo));
    }
  } catch (const core::Interrupted&) {
    // Finished points are committed; under MPI the other ranks stop too.
    if (world) {
      std::cerr << "uavsim: interrupted; finished points are kept\n";
      world->abort(130);
    }
    throw;
  }
  for (const SweepPointSpec& p : spec.points)
    if (!PointDone(o.out_dir, p.id)) ++out.missing;
  out.missing -= std::min(out.missing, out.failed);  // the rest: other shards' points
  RemoveStalePartials(o.out_dir, ShardIds(spec, o));
  if (out.missing == 0 && out.failed == 0) {
    const SweepOutcome merged = MergeSweep(o.out_dir);
    out.warnings = merged.warnings;
    out.reported = true;
    std::error_code ec;
    if (!o.keep_traces) fs::remove_all(fs::path(o.out_dir) / "traces", ec);
  }
  return out;
}

}  // namespace uavsim::sim
