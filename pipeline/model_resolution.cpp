#include "pipeline/model_resolution.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "pipeline/model_checksums.h"
#include "pipeline/variants.h"

namespace uavsim::pipeline {

const char* const kHowToTrain =
    "train one with `uavsim train SCENARIO.json --out DIR` and set /pipeline/model to DIR";

namespace {

// The manifest of the trained model the scenario names.
std::string ModelPath(const CatalogScenario& s) {
  namespace fs = std::filesystem;
  if (s.pipeline->model == "default") return DefaultModelPath();
  return ModelManifestPath((fs::path(s.base_dir) / s.pipeline->model).lexically_normal().string());
}

// Whether a model's folder (given by its manifest) vouches for its files.
bool HasChecksums(const std::string& manifest_path) {
  std::error_code ec;
  return std::filesystem::exists(
      std::filesystem::path(manifest_path).parent_path() / kModelChecksumsFile, ec);
}

void RequireModelFile(const std::string& file, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw core::ConfigError(file, "/pipeline/model",
                            "no trained model at " + path + ": " + kHowToTrain);
}

// The scenario's settings a model's manifest must agree with.
void CheckManifestFits(const CatalogScenario& s, const std::string& file, const std::string& path,
                       const ModelManifest& m) {
  if (m.latent_dim != s.pipeline->latent_dim)
    throw core::ConfigError(file, "/pipeline/latent_dim",
                            "the model " + path + " sends latents of " +
                                std::to_string(m.latent_dim) + " values, the scenario asks for " +
                                std::to_string(s.pipeline->latent_dim) + ": " + kHowToTrain);
  if (std::abs(m.window_s - s.pipeline->window_s) > 1e-12)
    throw core::ConfigError(file, "/pipeline/window_s",
                            "the model " + path + " was trained with " +
                                core::FormatNumber(m.window_s) +
                                " s windows, the scenario asks for " +
                                core::FormatNumber(s.pipeline->window_s) + " s: " + kHowToTrain);
}

// A listed method taken apart (the scenario was validated: it parses).
MethodName MethodOf(const std::string& method) {
  return ParseMethod(method).value_or(MethodName{});
}

// Each method's edge head is in the model (`heads`), and uavloc is asked of
// a paper-variant model: else a ConfigError naming the scenario's
// /pipeline/methods entry.
void RequireHeads(const CatalogScenario& s, const std::string& file, const std::string& path,
                  const ModelManifest& m, const EdgeHeads& heads) {
  for (std::size_t i = 0; i < s.pipeline->methods.size(); ++i) {
    const std::string& method = s.pipeline->methods[i];
    const std::string at = "/pipeline/methods/" + std::to_string(i);
    const bool paper = MethodOf(method).learned == "uavloc" || method == "uavloc_per_track";
    const bool anchored = method == "uavloc_anchored";
    if ((paper || anchored) && m.variant != "paper")
      throw core::ConfigError(file, at,
                              "the model " + path + " is the " + m.variant +
                                  " variant, not the paper's pipeline: list it as method " +
                                  VariantMethod(m.variant));
    if ((paper && heads.paper.empty()) || (anchored && heads.anchored.empty()))
      throw core::ConfigError(
          file, at,
          "the model " + path + " has no " + (paper ? "paper" : "anchored") + " head for `" +
              method + "` (" + (paper ? "uavloc is the paper's pipeline since issue 19" : "") +
              (paper ? "; " : "") +
              "train both with `uavsim train SCENARIO.json --head both --out DIR` and set "
              "/pipeline/model to DIR)");
  }
}

// A part's sidecar as JSON without its note (which says how its model was
// made, not what it is).
core::Json PartWithoutNote(const std::string& path) {
  core::Json j = core::LoadJsonFile(path);
  if (j.is_object()) j.erase("note");
  return j;
}

std::string FileBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// Whether two models' nodes send the same latents: the same encoder weights
// and configuration per modality.
bool SameEncoders(const ModelManifest& a, const std::string& a_path, const ModelManifest& b,
                  const std::string& b_path) {
  namespace fs = std::filesystem;
  const fs::path da = fs::path(a_path).parent_path(), db = fs::path(b_path).parent_path();
  const std::string* pa[] = {&a.camera, &a.lidar, &a.radar};
  const std::string* pb[] = {&b.camera, &b.lidar, &b.radar};
  for (int m = 0; m < 3; ++m) {
    const core::Json ja = PartWithoutNote((da / *pa[m]).string());
    const core::Json jb = PartWithoutNote((db / *pb[m]).string());
    if (ja != jb) return false;
    // The weights file the sidecar names (ib_model_io.h: "weights").
    if (!ja.contains("weights") || !ja["weights"].is_string()) return false;
    const std::string w = ja["weights"].get<std::string>();
    if (FileBytes((da / w).string()) != FileBytes((db / w).string())) return false;
  }
  return true;
}

// The models of the variants the scenario's methods run, by variant name,
// other than the scenario's own model (`main`, at `main_path`): each the
// folder beside it named FOLDER-VARIANT. Checked without loading weights:
// it exists with valid checksums, is that variant, fits the scenario, and
// its encoders are the scenario model's (the nodes run one encoder per
// modality). Throws core::ConfigError naming the method's
// /pipeline/methods entry.
std::map<std::string, std::string> VariantModelPaths(const CatalogScenario& s,
                                                     const std::string& file,
                                                     const ModelManifest& main,
                                                     const std::string& main_path) {
  namespace fs = std::filesystem;
  std::map<std::string, std::string> paths;
  for (std::size_t i = 0; i < s.pipeline->methods.size(); ++i) {
    const std::string learned = MethodOf(s.pipeline->methods[i]).learned;
    if (learned.empty() || learned == "uavloc") continue;
    const std::string variant = VariantOfMethod(learned);
    if (variant == main.variant || paths.count(variant)) continue;
    const std::string at = "/pipeline/methods/" + std::to_string(i);
    const fs::path folder = fs::path(main_path).parent_path();
    const std::string path = (fs::path(folder.string() + "-" + variant) / "model.json").string();
    const std::string how = "train it with `uavsim train " + file + " --variant " + variant +
                            " --encoders " + folder.string() + "`";
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
      throw core::ConfigError(file, at,
                              "no model of the " + variant + " variant at " + path + ": " + how);
    ModelManifest m;
    try {
      m = ReadModelManifest(path);
      VerifyModelChecksums(fs::path(path).parent_path().string());
    } catch (const core::ConfigError& e) {
      throw core::ConfigError(file, at, std::string(e.what()) + " (" + how + ")");
    }
    if (m.variant != variant)
      throw core::ConfigError(
          file, at,
          "the model " + path + " is the " + m.variant + " variant, not " + variant + ": " + how);
    CheckManifestFits(s, file, path, m);
    if (!SameEncoders(main, main_path, m, path))
      throw core::ConfigError(file, at,
                              "the model " + path + " has other encoders than /pipeline/model's " +
                                  main_path + " (the nodes run one encoder per modality): " + how +
                                  ", or run it as the scenario's model (/pipeline/model)");
    paths[variant] = path;
  }
  return paths;
}

// A raw-variant model was trained on what the nodes send without
// pre-processing: the scenario must send that.
void RequireRawFits(const CatalogScenario& s, const std::string& file, const std::string& path,
                    const ModelManifest& m) {
  const auto& p = s.pipeline->preprocess;
  if (m.variant == "raw" && !(p.CameraRaw() && p.LidarRaw() && p.RadarRaw()))
    throw core::ConfigError(file, "/pipeline/preprocess/raw",
                            "the model " + path +
                                " is the raw variant, trained on data without pre-processing: "
                                "set it to true");
}

// The scenario's own model, found and checked into `r`.
void ResolveModel(const CatalogScenario& s, ModelResolution& r) {
  const std::string& file = s.file;
  r.model_path = ModelPath(s);
  RequireModelFile(file, r.model_path);
  EdgeHeads heads;
  try {
    r.manifest = ReadModelManifest(r.model_path);
    VerifyModelChecksums(std::filesystem::path(r.model_path).parent_path().string());
    heads = ReadEdgeHeads(r.manifest, r.model_path);
  } catch (const core::ConfigError& e) {
    throw core::ConfigError(file, "/pipeline/model",
                            std::string(e.what()) + " (" + kHowToTrain + ")");
  }
  CheckManifestFits(s, file, r.model_path, r.manifest);
  RequireRawFits(s, file, r.model_path, r.manifest);
  RequireHeads(s, file, r.model_path, r.manifest, heads);
  if (!HasChecksums(r.model_path)) r.unchecked.push_back(r.model_path);
}

// Its variants' models.
void ResolveVariants(const CatalogScenario& s, ModelResolution& r) {
  r.variant_paths = VariantModelPaths(s, s.file, r.manifest, r.model_path);
  for (const auto& [variant, path] : r.variant_paths)
    if (!HasChecksums(path)) r.unchecked.push_back(path);
}

}  // namespace

bool NeedsTrainedModel(const PipelineConfig& p) {
  const auto& m = p.methods;
  if (!p.scripted.empty() || !p.hosted.empty()) return true;  // they run on the model's latents
  return std::any_of(m.begin(), m.end(), [](const std::string& method) {
    return !MethodOf(method).learned.empty() || method == "uavloc_anchored" ||
           method == "uavloc_per_track";
  });
}

std::string ResolveEncoderModel(const CatalogScenario& s, const std::string& dir,
                                const std::string& command) {
  const std::string& file = s.file;
  namespace fs = std::filesystem;
  std::error_code ec;
  const std::string path =
      dir == "default" && !fs::exists(dir, ec) ? DefaultModelPath() : ModelManifestPath(dir);
  const std::string what = command + ": --model " + dir + ": ";
  if (!fs::is_regular_file(path, ec))
    throw core::UsageError(what + "no trained model at " + path + " (" + kHowToTrain + ")");
  ModelManifest m;
  try {
    m = ReadModelManifest(path);
    const fs::path folder = fs::path(path).parent_path();
    VerifyModelChecksums(folder.empty() ? "." : folder.string());
  } catch (const core::ConfigError& e) {
    throw core::UsageError(what + e.what());
  }
  CheckManifestFits(s, file, path, m);
  RequireRawFits(s, file, path, m);
  return path;
}

ModelResolution ResolveModels(const CatalogScenario& s) {
  ModelResolution r;
  r.needs_model = NeedsTrainedModel(*s.pipeline);
  if (!r.needs_model) return r;
  ResolveModel(s, r);
  ResolveVariants(s, r);
  return r;
}

bool SendsAnchors(const PipelineConfig& p) {
  const auto& m = p.methods;
  return std::find(m.begin(), m.end(), "uavloc_anchored") != m.end() ||
         std::find(m.begin(), m.end(), "anchor_track") != m.end() ||
         std::find(m.begin(), m.end(), "mtt") != m.end() ||
         std::find(m.begin(), m.end(), "mtt_jpda") != m.end() ||
         std::find(m.begin(), m.end(), "uavloc_per_track") != m.end();
}

std::string VariantOfMethod(const std::string& learned) {
  return learned == "uavloc" ? "paper" : learned;
}

}  // namespace uavsim::pipeline
