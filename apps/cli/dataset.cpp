// `uavsim dataset`: the training episodes as one HDF5 file.
#include <cstdio>
#include <iostream>

#include "apps/cli/cli.h"
#include "apps/dataset/dataset_export.h"
#include "core/error.h"
#include "sim/scenario.h"

namespace uavsim::cli {
using core::UsageError;

int RunDatasetCommand(const ParsedArgs& a, int, char**) {
  const std::string& file = OneScenario("dataset", a);
  sim::DatasetCommand c;
  c.scenario_file = file;
  c.force = a.Has("--force");
  c.quiet = a.Has("--quiet");
  if (!a.Value("--out") || a.Value("--out")->empty())
    throw UsageError("uavsim dataset: --out FILE.h5 is required (see uavsim dataset --help)");
  c.out_file = *a.Value("--out");
  c.model = a.Value("--model").value_or("");
  c.data_file = a.Value("--data").value_or("");
  if (auto v = a.Value("--seed")) c.seed = UnsignedOption("dataset", "--seed", *v, ~0ull >> 1);
  if (auto v = a.Value("--episodes"))
    c.episodes = static_cast<int>(UnsignedOption("dataset", "--episodes", *v, 100000));
  if (auto v = a.Value("--jobs"))
    c.jobs = static_cast<int>(UnsignedOption("dataset", "--jobs", *v, 1024));
  if (auto v = a.Value("--episode-s"))
    c.episode_s = NumberOption("dataset", "--episode-s", *v, 1.0, 3600.0, "seconds from 1 to 3600");
  if ((a.Value("--episodes") && c.episodes < 1) || c.jobs < 1)
    throw UsageError("uavsim dataset: --episodes and --jobs need at least 1");
  const sim::Scenario s = sim::LoadScenario(file, Overrides(a));
  const std::optional<sim::DatasetSummary> r = sim::RunDatasetExport(s, c);
  if (!r || c.quiet) return kExitOk;  // an MPI rank that only simulated episodes
  std::size_t frames = 0;
  for (std::size_t n : r->frames) frames += n;
  std::printf(
      "%s: %zu episodes of %g s, %zu frames (camera %zu, lidar %zu, radar %zu; %.1f %% on time)",
      c.out_file.c_str(), r->episodes, r->episode_s, frames, r->frames[0], r->frames[1],
      r->frames[2],
      frames ? 100.0 * static_cast<double>(r->on_time) / static_cast<double>(frames) : 0.0);
  if (r->latent_dim > 0)
    std::printf(", latents of %lld values", static_cast<long long>(r->latent_dim));
  std::printf(", %.1f MB\n", static_cast<double>(r->bytes) / 1e6);
  return kExitOk;
}

}  // namespace uavsim::cli
