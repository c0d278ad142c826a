// `uavsim train`: the UAVLoc model (and the paper's variants) trained by
// simulation; prints the held-out scores beside the information limit.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>

#include "apps/cli/cli.h"
#include "apps/train/train.h"
#include "core/error.h"
#include "pipeline/variants.h"
#include "sim/scenario.h"

namespace uavsim::cli {
namespace {

using core::UsageError;

// The command's numbers and files (the scenario file, seeds, counts).
sim::TrainCommand ParseTrainOptions(const ParsedArgs& a, int argc, char** argv) {
  RefuseReplacedTrainFlags(a);
  sim::TrainCommand c;
  c.scenario_file = OneScenario("train", a);
  c.command_line = CommandLine(argc, argv);
  c.quick = a.Has("--quick");
  c.quiet = a.Has("--quiet");
  c.force = a.Has("--force");
  c.data_file = a.Value("--data").value_or("");
  c.wait = a.Has("--wait");
  if (auto v = a.Value("--seed")) c.seed = UnsignedOption("train", "--seed", *v, ~0ull >> 1);
  if (auto v = a.Value("--data-seed"))
    c.data_seed = UnsignedOption("train", "--data-seed", *v, ~0ull >> 1);
  if (auto v = a.Value("--episodes"))
    c.episodes = static_cast<int>(UnsignedOption("train", "--episodes", *v, 100000));
  if (auto v = a.Value("--threads"))
    c.threads = static_cast<int>(UnsignedOption("train", "--threads", *v, 256));
  if (auto v = a.Value("--jobs"))
    c.jobs = static_cast<int>(UnsignedOption("train", "--jobs", *v, 1024));
  if (auto v = a.Value("--episode-s"))
    c.episode_s = NumberOption("train", "--episode-s", *v, 1.0, 3600.0, "seconds from 1 to 3600");
  return c;
}

// The variant, the heads, the split and the training config; returns the variant.
const pipeline::Variant& ParseTrainVariant(const ParsedArgs& a, sim::TrainCommand& c) {
  // --bottleneck mlp is the older spelling of --variant mlp_bottleneck.
  const bool mlp_flag = a.Value("--bottleneck") && *a.Value("--bottleneck") == "mlp";
  const std::string variant_name =
      a.Value("--variant").value_or(mlp_flag ? "mlp_bottleneck" : "paper");
  const pipeline::Variant* variant = pipeline::FindVariant(variant_name);
  if (!variant)
    throw UsageError("uavsim train: --variant expects one of " + pipeline::VariantNames() +
                     ", got '" + variant_name + "'");
  c.variant = variant_name;
  c.mlp_bottleneck = variant->mlp_bottleneck;
  if (variant_name != "paper") c.anchored_head = false;  // ours extends the paper's design only
  if (variant_name != "paper" && a.Value("--head") && *a.Value("--head") != "paper" &&
      *a.Value("--head") != "none")
    throw UsageError("uavsim train: --variant " + variant_name +
                     " trains the paper's head only (--head paper); the anchored head "
                     "extends the paper variant");
  if (a.Value("--bottleneck") && variant->mlp_bottleneck != mlp_flag)
    throw UsageError("uavsim train: --bottleneck " + *a.Value("--bottleneck") +
                     " contradicts --variant " + variant_name +
                     " (--bottleneck mlp is --variant mlp_bottleneck)");
  if (auto v = a.Value("--encoders")) c.encoders_dir = *v;  // checked against the variant
  if (auto v = a.Value("--bottleneck")) {
    if (*v != "ib" && *v != "mlp")
      throw UsageError("uavsim train: --bottleneck expects ib or mlp, got '" + *v + "'");
  }
  if (auto v = a.Value("--head")) {
    if (*v != "anchored" && *v != "paper" && *v != "both" && *v != "none")
      throw UsageError("uavsim train: --head expects both, paper, anchored or none, got '" + *v +
                       "'");
    c.paper_head = *v == "paper" || *v == "both";
    c.anchored_head = (*v == "anchored" || *v == "both") && variant_name == "paper";
  }
  if (auto v = a.Value("--split")) {
    if (*v != "trajectory" && *v != "frame")
      throw UsageError("uavsim train: --split expects trajectory or frame, got '" + *v + "'");
    c.split = *v == "frame" ? pipeline::DataSplit::kFrame : pipeline::DataSplit::kTrajectory;
  }
  if (auto v = a.Value("--train-episodes"))
    c.train_episodes = static_cast<int>(UnsignedOption("train", "--train-episodes", *v, 100000));
  if ((a.Value("--episodes") && c.episodes < 3) || (a.Value("--threads") && c.threads < 1) ||
      c.jobs < 1)
    throw UsageError(
        "uavsim train: --episodes needs at least 3 (training, validation, test), --threads and "
        "--jobs at least 1");
  c.training = sim::ResolveTrainingConfig(c.quick, a.Value("--config").value_or(""),
                                          a.Values("--config-set"), variant);
  return *variant;
}

// The stages, held-out scores and information limit, on stdout.
void PrintTrainReport(const sim::TrainCommand& c, const pipeline::TrainReport& r) {
  for (const auto& st : r.stages)
    std::printf("%-15s %5zu train %5zu val  epochs %3d (best %3d)  val loss %.4g -> %.4g  %.0f s\n",
                st.name.c_str(), st.train_items, st.validation_items, st.epochs, st.best_epoch,
                st.initial_validation_loss, st.best_validation_loss, st.seconds);
  for (const auto& [method, ev] : r.test) {
    std::printf("held-out RMSE of %s (m):", method.c_str());
    for (const auto& [k, v] : ev.rmse_m) std::printf(" %s %.3f", k.c_str(), v);
    std::printf("\n");
  }
  if (!r.test_decoder.empty()) {
    std::printf("held-out RMSE of each node's IB decoder alone, no fusion (m):");
    for (const auto& [modality, d] : r.test_decoder)
      std::printf(" %s %.3f (%zu obs.)", modality.c_str(), d.rmse_m, d.observations);
    std::printf("\n");
    // The information limit beside it: the same on-target observations'
    // centroid (the camera: its ray at the true range).
    for (const auto& [modality, d] : r.test_decoder)
      std::printf(
          "  %-6s on target %.3f (%zu obs.), centroid of the same %.3f; off target %.3f (%zu "
          "obs.)\n",
          modality.c_str(), d.on_target_rmse_m, d.on_target, d.centroid_on_target_m,
          d.off_target_rmse_m, d.off_target);
    std::printf("validation on target (what stage-1 settings are chosen on):");
    for (const auto& [modality, d] : r.validation_decoder)
      std::printf(" %s %.3f vs centroid %.3f (%zu obs.)", modality.c_str(), d.on_target_rmse_m,
                  d.centroid_on_target_m, d.on_target);
    std::printf("\n");
    std::printf("held-out observations holding the target (of those sent):");
    for (const auto& [modality, weathers] : r.test_sent)
      for (const auto& [weather, c] : weathers)
        std::printf(" %s/%s %zu of %zu", modality.c_str(), weather.c_str(), c.holding_target,
                    c.sent);
    std::printf("\n");
  }
  if (r.test_common.size() > 1) {
    std::size_t fewest = ~std::size_t{0}, most = 0;
    for (const auto& [method, ev] : r.test) {
      fewest = std::min(fewest, ev.windows.at("all"));
      most = std::max(most, ev.windows.at("all"));
    }
    std::printf(
        "held-out RMSE on the windows every method counted (m; all: %zu windows, each method "
        "alone %zu to %zu):\n",
        r.test_common.begin()->second.windows.at("all"), fewest, most);
    for (const auto& [method, ev] : r.test_common) {
      std::printf("  %-16s", method.c_str());
      for (const auto& [k, v] : ev.rmse_m) std::printf(" %s %.3f", k.c_str(), v);
      std::printf("\n");
    }
  }
  std::printf("model written to %s (use: --set /pipeline/model=%s)\n", c.out_dir.c_str(),
              c.out_dir.c_str());
}

}  // namespace

int RunTrainCommand(const ParsedArgs& a, int argc, char** argv) {
  sim::TrainCommand c = ParseTrainOptions(a, argc, argv);
  const pipeline::Variant& variant = ParseTrainVariant(a, c);
  sim::Scenario s = sim::LoadScenario(c.scenario_file, Overrides(a));
  sim::ApplyVariantNodes(variant, s);  // e.g. raw: "without preprocessing"
  c.out_dir =
      a.Value("--out").value_or("models/" + s.name + (c.variant == "paper" ? "" : "-" + c.variant));
  const std::optional<pipeline::TrainReport> report = sim::RunTraining(s, c);
  if (!report) return kExitOk;  // an MPI rank that only simulated episodes
  if (!c.quiet) PrintTrainReport(c, *report);
  return kExitOk;
}

}  // namespace uavsim::cli
