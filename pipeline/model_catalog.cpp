#include "pipeline/model_catalog.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>

#include "pipeline/edge/edge_localizer.h"
#include "pipeline/edge/scripted_edge.h"
#include "pipeline/model_checksums.h"
#include "pipeline/variants.h"

namespace uavsim::pipeline {
namespace {

const char* const kHowToTrain =
    "train one with `uavsim train SCENARIO.json --out DIR` and set /pipeline/model to DIR";

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

// Where the model departs from the paper's design (Secs. IV-V): the training
// config's switches of our extensions, as "key=value"; empty, the paper's
// design throughout; null for a model without a recorded config. The
// temporal regressor is not among them (a GRU, LSTM or TCN is the paper's
// own baseline, Sec. VI): TemporalOf names it.
core::Json ExtensionsOf(const ModelManifest& m) {
  if (!m.training) return nullptr;
  const TrainingConfig& t = *m.training;
  core::Json ext = core::Json::array();
  if (t.camera_stereo_branches != StereoBranches::kTwo)
    ext.push_back("camera_stereo_branches=shared");
  if (t.camera_eye_pool_side != 0)
    ext.push_back("camera_eye_pool_side=" + std::to_string(t.camera_eye_pool_side));
  if (t.camera_roi_geometry) ext.push_back("camera_roi_geometry=true");
  if (t.te_align_tau_origin != TauOrigin::kClock) ext.push_back("te_align_tau_origin=window");
  if (t.point_frame != PointFrame::kScene)
    ext.push_back(std::string("point_frame=") + PointFrameName(t.point_frame));
  if (t.point_norm != PointNorm::kBatch)
    ext.push_back(std::string("point_norm=") + PointNormName(t.point_norm));
  if (t.ib_mse_units != IbMseUnits::kMetres)
    ext.push_back(std::string("ib_mse_units=") + IbMseUnitsName(t.ib_mse_units));
  // The IB-CC models' dropout rate; the paper's is 0.1 (Sec. VI).
  if (t.dropout != 0.1) ext.push_back("dropout=" + core::FormatNumber(t.dropout));
  // Stage 1 left out observations whose cluster or bearing missed the truth.
  if (t.stage1_label_gate_m > 0.0)
    ext.push_back("stage1_label_gate_m=" + core::FormatNumber(t.stage1_label_gate_m));
  if (t.stage1_label_gate_deg > 0.0)
    ext.push_back("stage1_label_gate_deg=" + core::FormatNumber(t.stage1_label_gate_deg));
  return ext;
}

// Where the scenario's sensing nodes depart from the paper's pre-processing
// (Sec. IV-A): the switches of ours that are on (the model was trained on
// them: the layout hash says so), as "key=value".
core::Json NodeExtensionsOf(const PreprocessConfig& p) {
  core::Json ext = core::Json::array();
  if (p.lidar.weather_echo_rejection) ext.push_back("lidar.weather_echo_rejection=true");
  if (p.radar.rain_doppler_rejection) ext.push_back("radar.rain_doppler_rejection=true");
  if (p.radar.selection != RadarSelection::kLargest)
    ext.push_back(std::string("radar.selection=") + RadarSelectionName(p.radar.selection));
  if (p.max_observations > 1)
    ext.push_back("max_observations=" + std::to_string(p.max_observations));
  return ext;
}

// The model's temporal regressor ("mamba", the paper's, or one of its
// baselines); models without a recorded config predate the choice: "mamba".
const char* TemporalOf(const ModelManifest& m) {
  return TemporalKindName(m.training ? m.training->temporal : TemporalKind::kMamba);
}

// A listed method taken apart (the scenario was validated: it parses).
MethodName MethodOf(const std::string& method) {
  return ParseMethod(method).value_or(MethodName{});
}

// The variant a learned method runs ("paper" for uavloc).
std::string VariantOfMethod(const std::string& learned) {
  return learned == "uavloc" ? "paper" : learned;
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

// The scenario's TorchScript methods, loaded and their signatures checked:
// else a ConfigError naming the entry's /pipeline/methods/i/edge.
std::map<std::string, std::unique_ptr<ScriptedEdge>> LoadScriptedEdges(const CatalogScenario& s,
                                                                       const std::string& file) {
  namespace fs = std::filesystem;
  std::map<std::string, std::unique_ptr<ScriptedEdge>> loaded;
  for (std::size_t i = 0; i < s.pipeline->methods.size(); ++i) {
    const ScriptedMethod* m = s.pipeline->FindScripted(s.pipeline->methods[i]);
    if (!m) continue;
    const std::string path = (fs::path(s.base_dir) / m->edge).lexically_normal().string();
    try {
      loaded[m->name] = ScriptedEdge::Load(path, s.pipeline->latent_dim, s.pipeline->window_s);
    } catch (const std::invalid_argument& e) {
      throw core::ConfigError(file, "/pipeline/methods/" + std::to_string(i) + "/edge", e.what());
    }
  }
  return loaded;
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

ModelCatalog::ModelCatalog(CatalogScenario s) : s_(std::move(s)) {
  needs_model_ = NeedsTrainedModel(*s_.pipeline);
  if (!needs_model_) return;
  ResolveModel();
  ResolveVariants();
}

ModelCatalog::~ModelCatalog() = default;
ModelCatalog::ModelCatalog(ModelCatalog&&) noexcept = default;

void ModelCatalog::ResolveModel() {
  const std::string& file = s_.file;
  model_path_ = ModelPath(s_);
  RequireModelFile(file, model_path_);
  EdgeHeads heads;
  try {
    manifest_ = ReadModelManifest(model_path_);
    VerifyModelChecksums(std::filesystem::path(model_path_).parent_path().string());
    heads = ReadEdgeHeads(manifest_, model_path_);
  } catch (const core::ConfigError& e) {
    throw core::ConfigError(file, "/pipeline/model",
                            std::string(e.what()) + " (" + kHowToTrain + ")");
  }
  CheckManifestFits(s_, file, model_path_, manifest_);
  RequireRawFits(s_, file, model_path_, manifest_);
  RequireHeads(s_, file, model_path_, manifest_, heads);
  if (!HasChecksums(model_path_)) unchecked_.push_back(model_path_);
}

void ModelCatalog::ResolveVariants() {
  variant_paths_ = VariantModelPaths(s_, s_.file, manifest_, model_path_);
  for (const auto& [variant, path] : variant_paths_)
    if (!HasChecksums(path)) unchecked_.push_back(path);
}

void ModelCatalog::LoadScripted() {
  if (scripted_.empty()) scripted_ = LoadScriptedEdges(s_, s_.file);
}

void ModelCatalog::Load(bool quiet) {
  if (!needs_model_ || model_) return;
  try {
    model_ = UavLocModelFiles::Load(model_path_);
  } catch (const core::ConfigError& e) {
    throw core::ConfigError(s_.file, "/pipeline/model",
                            std::string(e.what()) + " (" + kHowToTrain + ")");
  }
  const ModelManifest& m = model_->manifest();
  const bool same_layout = m.layout_hash == s_.layout_hash;
  if (!same_layout && !quiet)
    std::cerr << "uavsim: warning: the model " << model_path_ << " was trained for scenario \""
              << m.scenario << "\" with another world or node layout; its estimates may be poor ("
              << kHowToTrain << ")\n";
  core::Json heads = core::Json::array();
  if (!model_->heads().paper.empty()) heads.push_back("paper");
  if (!model_->heads().anchored.empty()) heads.push_back("anchored");
  info_ = {{"path", model_path_},
           {"trained_for", m.scenario},
           {"same_layout", same_layout},
           {"heads", heads},
           {"extensions", ExtensionsOf(m)}};
  if (info_["extensions"].is_array())
    for (const core::Json& e : NodeExtensionsOf(s_.pipeline->preprocess))
      info_["extensions"].push_back(e);
  const auto& methods = s_.pipeline->methods;
  if (info_["extensions"].is_array() &&
      std::find(methods.begin(), methods.end(), "uavloc_per_track") != methods.end())
    info_["extensions"].push_back("method=uavloc_per_track");
  info_["temporal"] = TemporalOf(m);
  info_["variant"] = m.variant;
  for (const auto& [variant, path] : variant_paths_) {
    variant_models_[variant] = UavLocModelFiles::Load(path);
    info_["variants"][variant] = path;
  }
  LoadScripted();
  for (const auto& [name, edge] : scripted_)
    info_["scripted"][name] = s_.pipeline->FindScripted(name)->edge;
}

const NodeEncoder* ModelCatalog::encoder(core::Modality m) const {
  return model_ ? &model_->encoder(m) : nullptr;
}

std::unique_ptr<LocalizationMethod> ModelCatalog::MakeMethod(const std::string& name) {
  if (const auto it = scripted_.find(name); it != scripted_.end())
    return it->second ? MakeScriptedMethod(name, std::move(it->second)) : nullptr;
  if (!model_) return nullptr;
  if (name == "uavloc_anchored") {
    std::unique_ptr<EdgeLocalizer> edge = model_->LoadEdge(true);
    edge->WaitForTrack(s_.pipeline->uavloc_wait_for_track);
    return MakeLearnedMethod(name, std::move(edge), kModalitySubsets, /*anchored=*/true);
  }
  if (name == "uavloc_per_track") {
    const UavLocModelFiles* files = model_.get();
    return MakePerTrackMethod(s_.pipeline->window_s,
                              [files] { return files->LoadEdge(/*anchored=*/false); });
  }
  const MethodName method = MethodOf(name);
  if (method.learned.empty()) return nullptr;
  const std::string variant = VariantOfMethod(method.learned);
  const UavLocModelFiles& files =
      variant == manifest_.variant ? *model_ : *variant_models_.at(variant);
  return MakeLearnedMethod(name, files.LoadEdge(false), method.modalities, /*anchored=*/false);
}

bool SendsAnchors(const PipelineConfig& p) {
  const auto& m = p.methods;
  return std::find(m.begin(), m.end(), "uavloc_anchored") != m.end() ||
         std::find(m.begin(), m.end(), "anchor_track") != m.end() ||
         std::find(m.begin(), m.end(), "mtt") != m.end() ||
         std::find(m.begin(), m.end(), "mtt_jpda") != m.end() ||
         std::find(m.begin(), m.end(), "uavloc_per_track") != m.end();
}

}  // namespace uavsim::pipeline
