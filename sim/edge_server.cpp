#include "sim/edge_server.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>

#include "pipeline/anchored/geometric_anchor.h"
#include "pipeline/edge/scripted_edge.h"
#include "pipeline/model_checksums.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/torch_runtime.h"
#include "pipeline/training/trainer.h"
#include "pipeline/variants.h"

namespace uavsim::sim {
namespace {

const char* const kHowToTrain =
    "train one with `uavsim train SCENARIO.json --out DIR` and set /pipeline/model to DIR";

// The manifest of the trained model the scenario names.
std::string ModelPath(const Scenario& s) {
  namespace fs = std::filesystem;
  if (s.pipeline.model == "default") return pipeline::DefaultModelPath();
  return pipeline::ModelManifestPath(
      (fs::path(s.base_dir) / s.pipeline.model).lexically_normal().string());
}

// Whether a model's folder (given by its manifest) vouches for its files.
bool HasChecksums(const std::string& manifest_path) {
  std::error_code ec;
  return std::filesystem::exists(
      std::filesystem::path(manifest_path).parent_path() / pipeline::kModelChecksumsFile, ec);
}

void RequireModelFile(const std::string& file, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw core::ConfigError(file, "/pipeline/model",
                            "no trained model at " + path + ": " + kHowToTrain);
}

// The scenario's settings a model's manifest must agree with.
void CheckManifestFits(const Scenario& s, const std::string& file, const std::string& path,
                       const pipeline::ModelManifest& m) {
  if (m.latent_dim != s.pipeline.latent_dim)
    throw core::ConfigError(file, "/pipeline/latent_dim",
                            "the model " + path + " sends latents of " +
                                std::to_string(m.latent_dim) + " values, the scenario asks for " +
                                std::to_string(s.pipeline.latent_dim) + ": " + kHowToTrain);
  if (std::abs(m.window_s - s.pipeline.window_s) > 1e-12)
    throw core::ConfigError(file, "/pipeline/window_s",
                            "the model " + path + " was trained with " +
                                core::FormatNumber(m.window_s) +
                                " s windows, the scenario asks for " +
                                core::FormatNumber(s.pipeline.window_s) + " s: " + kHowToTrain);
}

// Where the model departs from the paper's design (Secs. IV-V): the training
// config's switches of our extensions, as "key=value"; empty, the paper's
// design throughout; null for a model without a recorded config. The
// temporal regressor is not among them (a GRU, LSTM or TCN is the paper's
// own baseline, Sec. VI): TemporalOf names it.
core::Json ExtensionsOf(const pipeline::ModelManifest& m) {
  if (!m.training) return nullptr;
  const pipeline::TrainingConfig& t = *m.training;
  core::Json ext = core::Json::array();
  if (t.camera_stereo_branches != pipeline::StereoBranches::kTwo)
    ext.push_back("camera_stereo_branches=shared");
  if (t.camera_eye_pool_side != 0)
    ext.push_back("camera_eye_pool_side=" + std::to_string(t.camera_eye_pool_side));
  if (t.camera_roi_geometry) ext.push_back("camera_roi_geometry=true");
  if (t.te_align_tau_origin != pipeline::TauOrigin::kClock)
    ext.push_back("te_align_tau_origin=window");
  if (t.point_frame != pipeline::PointFrame::kScene)
    ext.push_back(std::string("point_frame=") + pipeline::PointFrameName(t.point_frame));
  if (t.point_norm != pipeline::PointNorm::kBatch)
    ext.push_back(std::string("point_norm=") + pipeline::PointNormName(t.point_norm));
  if (t.ib_mse_units != pipeline::IbMseUnits::kMetres)
    ext.push_back(std::string("ib_mse_units=") + pipeline::IbMseUnitsName(t.ib_mse_units));
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
core::Json NodeExtensionsOf(const pipeline::PreprocessConfig& p) {
  core::Json ext = core::Json::array();
  if (p.lidar.weather_echo_rejection) ext.push_back("lidar.weather_echo_rejection=true");
  if (p.radar.rain_doppler_rejection) ext.push_back("radar.rain_doppler_rejection=true");
  if (p.radar.selection != pipeline::RadarSelection::kLargest)
    ext.push_back(std::string("radar.selection=") +
                  pipeline::RadarSelectionName(p.radar.selection));
  return ext;
}

// The model's temporal regressor ("mamba", the paper's, or one of its
// baselines); models without a recorded config predate the choice: "mamba".
const char* TemporalOf(const pipeline::ModelManifest& m) {
  return pipeline::TemporalKindName(m.training ? m.training->temporal
                                               : pipeline::TemporalKind::kMamba);
}

// The trained model a scenario names, loaded for the run loop. Throws
// core::ConfigError naming the scenario's /pipeline/model when it is missing
// or does not fit the scenario.
std::unique_ptr<pipeline::UavLocModelFiles> LoadModel(const Scenario& s, const std::string& file,
                                                      bool quiet, core::Json& info) {
  const std::string path = ModelPath(s);
  RequireModelFile(file, path);
  std::unique_ptr<pipeline::UavLocModelFiles> model;
  try {
    model = pipeline::UavLocModelFiles::Load(path);
  } catch (const core::ConfigError& e) {
    throw core::ConfigError(file, "/pipeline/model",
                            std::string(e.what()) + " (" + kHowToTrain + ")");
  }
  const pipeline::ModelManifest& m = model->manifest();
  CheckManifestFits(s, file, path, m);
  const bool same_layout = m.layout_hash == LayoutHash(s);
  if (!same_layout && !quiet)
    std::cerr << "uavsim: warning: the model " << path << " was trained for scenario \""
              << m.scenario << "\" with another world or node layout; its estimates may be poor ("
              << kHowToTrain << ")\n";
  core::Json heads = core::Json::array();
  if (!model->heads().paper.empty()) heads.push_back("paper");
  if (!model->heads().anchored.empty()) heads.push_back("anchored");
  info = {{"path", path},
          {"trained_for", m.scenario},
          {"same_layout", same_layout},
          {"heads", heads},
          {"extensions", ExtensionsOf(m)}};
  if (info["extensions"].is_array())
    for (const core::Json& e : NodeExtensionsOf(s.pipeline.preprocess))
      info["extensions"].push_back(e);
  info["temporal"] = TemporalOf(m);
  return model;
}

// A listed method taken apart (the scenario was validated: it parses).
pipeline::MethodName MethodOf(const std::string& method) {
  return pipeline::ParseMethod(method).value_or(pipeline::MethodName{});
}

// The variant a learned method runs ("paper" for uavloc).
std::string VariantOfMethod(const std::string& learned) {
  return learned == "uavloc" ? "paper" : learned;
}

// Each method's edge head is in the model (`heads`), and uavloc is asked of
// a paper-variant model: else a ConfigError naming the scenario's
// /pipeline/methods entry.
void RequireHeads(const Scenario& s, const std::string& file, const std::string& path,
                  const pipeline::ModelManifest& m, const pipeline::EdgeHeads& heads) {
  for (std::size_t i = 0; i < s.pipeline.methods.size(); ++i) {
    const std::string& method = s.pipeline.methods[i];
    const std::string at = "/pipeline/methods/" + std::to_string(i);
    const bool paper = MethodOf(method).learned == "uavloc", anchored = method == "uavloc_anchored";
    if ((paper || anchored) && m.variant != "paper")
      throw core::ConfigError(file, at,
                              "the model " + path + " is the " + m.variant +
                                  " variant, not the paper's pipeline: list it as method " +
                                  pipeline::VariantMethod(m.variant));
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
bool SameEncoders(const pipeline::ModelManifest& a, const std::string& a_path,
                  const pipeline::ModelManifest& b, const std::string& b_path) {
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
std::map<std::string, std::string> VariantModelPaths(const Scenario& s, const std::string& file,
                                                     const pipeline::ModelManifest& main,
                                                     const std::string& main_path) {
  namespace fs = std::filesystem;
  std::map<std::string, std::string> paths;
  for (std::size_t i = 0; i < s.pipeline.methods.size(); ++i) {
    const std::string learned = MethodOf(s.pipeline.methods[i]).learned;
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
    pipeline::ModelManifest m;
    try {
      m = pipeline::ReadModelManifest(path);
      pipeline::VerifyModelChecksums(fs::path(path).parent_path().string());
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
void RequireRawFits(const Scenario& s, const std::string& file, const std::string& path,
                    const pipeline::ModelManifest& m) {
  const auto& p = s.pipeline.preprocess;
  if (m.variant == "raw" && !(p.CameraRaw() && p.LidarRaw() && p.RadarRaw()))
    throw core::ConfigError(file, "/pipeline/preprocess/raw",
                            "the model " + path +
                                " is the raw variant, trained on data without pre-processing: "
                                "set it to true");
}

// The scenario's TorchScript methods, loaded and their signatures checked:
// else a ConfigError naming the entry's /pipeline/methods/i/edge.
std::map<std::string, std::unique_ptr<pipeline::ScriptedEdge>> LoadScripted(
    const Scenario& s, const std::string& file) {
  namespace fs = std::filesystem;
  std::map<std::string, std::unique_ptr<pipeline::ScriptedEdge>> loaded;
  for (std::size_t i = 0; i < s.pipeline.methods.size(); ++i) {
    const pipeline::ScriptedMethod* m = s.pipeline.FindScripted(s.pipeline.methods[i]);
    if (!m) continue;
    const std::string path = (fs::path(s.base_dir) / m->edge).lexically_normal().string();
    try {
      loaded[m->name] =
          pipeline::ScriptedEdge::Load(path, s.pipeline.latent_dim, s.pipeline.window_s);
    } catch (const std::invalid_argument& e) {
      throw core::ConfigError(file, "/pipeline/methods/" + std::to_string(i) + "/edge", e.what());
    }
  }
  return loaded;
}

}  // namespace

std::unique_ptr<pipeline::Ekf> MakeEkf(const Scenario& s) {
  pipeline::EkfConfig config = s.pipeline.ekf;
  config.max_speed_mps = s.uavs.front().trajectory.max_speed_mps;
  config.max_accel_mps2 = s.uavs.front().trajectory.max_accel_mps2;
  config.target_size_m = s.uavs.front().size_m;
  auto ekf = std::make_unique<pipeline::Ekf>(config);
  for (const NodeConfig& n : s.nodes) {
    switch (n.sensor.type) {
      case sensors::SensorType::kFisheyeStereo:
        ekf->AddCamera(n.id, n.sensor.fisheye);
        break;
      case sensors::SensorType::kLidar:
        ekf->AddLidar(n.id, n.sensor.lidar);
        break;
      case sensors::SensorType::kFmcwRadar:
        ekf->AddRadar(n.id, n.sensor.radar);
        break;
    }
  }
  return ekf;
}

bool NeedsTrainedModel(const Scenario& s) {
  const auto& m = s.pipeline.methods;
  if (!s.pipeline.scripted.empty()) return true;  // they run on the model's latents
  return std::any_of(m.begin(), m.end(), [](const std::string& method) {
    return !MethodOf(method).learned.empty() || method == "uavloc_anchored";
  });
}

void CheckTrainedModel(const Scenario& s, const std::string& file, bool quiet) {
  if (!NeedsTrainedModel(s)) return;
  const std::string path = ModelPath(s);
  RequireModelFile(file, path);
  pipeline::ModelManifest m;
  pipeline::EdgeHeads heads;
  try {
    m = pipeline::ReadModelManifest(path);
    pipeline::VerifyModelChecksums(std::filesystem::path(path).parent_path().string());
    heads = pipeline::ReadEdgeHeads(m, path);
  } catch (const core::ConfigError& e) {
    throw core::ConfigError(file, "/pipeline/model",
                            std::string(e.what()) + " (" + kHowToTrain + ")");
  }
  CheckManifestFits(s, file, path, m);
  RequireRawFits(s, file, path, m);
  RequireHeads(s, file, path, m, heads);
  std::vector<std::string> unchecked;  // folders without checksums.sha256
  if (!HasChecksums(path)) unchecked.push_back(path);
  for (const auto& [variant, variant_path] : VariantModelPaths(s, file, m, path))
    if (!HasChecksums(variant_path)) unchecked.push_back(variant_path);
  pipeline::InitTorch(1, s.seed);
  LoadScripted(s, file);
  if (unchecked.empty()) return;
  // Nothing vouches for such a folder's files (a truncated radar.pt passed
  // validate, issue 43): they are checked as the run reads them, by
  // loading every one the run loads.
  { const EdgeServer loaded(s, file, /*quiet=*/true, /*methods=*/true); }
  if (!quiet)
    for (const std::string& p : unchecked)
      std::cerr << file << ": /pipeline/model: warning: " << p << ": its folder has no "
                << pipeline::kModelChecksumsFile
                << " (a model from before they were kept): checked by loading it\n";
}

std::string CheckEncoderModel(const Scenario& s, const std::string& file, const std::string& dir,
                              const std::string& command) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const std::string path = dir == "default" && !fs::exists(dir, ec)
                               ? pipeline::DefaultModelPath()
                               : pipeline::ModelManifestPath(dir);
  const std::string what = command + ": --model " + dir + ": ";
  if (!fs::is_regular_file(path, ec))
    throw core::UsageError(what + "no trained model at " + path + " (" + kHowToTrain + ")");
  pipeline::ModelManifest m;
  try {
    m = pipeline::ReadModelManifest(path);
    const fs::path folder = fs::path(path).parent_path();
    pipeline::VerifyModelChecksums(folder.empty() ? "." : folder.string());
  } catch (const core::ConfigError& e) {
    throw core::UsageError(what + e.what());
  }
  CheckManifestFits(s, file, path, m);
  RequireRawFits(s, file, path, m);
  return path;
}

EdgeServer::EdgeServer(const Scenario& s, const std::string& scenario_file, bool quiet,
                       bool methods)
    : scenario_(s),
      receiver_(s.pipeline.window_s, s.pipeline.late_allowance_s),
      window_ns_(core::Seconds(s.pipeline.window_s)) {
  if (!methods) return;
  if (Runs("ekf")) ekf_ = MakeEkf(s);
  if (Runs("anchor_track"))
    anchor_track_ = std::make_unique<pipeline::AnchorTrack>(s.pipeline.window_s);
  if (!NeedsTrainedModel(s)) return;
  pipeline::InitTorch(1, s.seed);
  model_ = LoadModel(s, scenario_file, quiet, model_info_);
  const pipeline::ModelManifest& main = model_->manifest();
  RequireRawFits(s, scenario_file, model_->manifest_path(), main);
  RequireHeads(s, scenario_file, model_->manifest_path(), main, model_->heads());
  model_info_["variant"] = main.variant;
  for (const auto& [variant, path] :
       VariantModelPaths(s, scenario_file, main, model_->manifest_path())) {
    variant_models_[variant] = pipeline::UavLocModelFiles::Load(path);
    model_info_["variants"][variant] = path;
  }
  if (Runs("uavloc")) uavloc_ = model_->LoadEdge(false);
  if (Runs("uavloc_anchored")) {
    uavloc_anchored_ = model_->LoadEdge(true);
    uavloc_anchored_->WaitForTrack(s.pipeline.uavloc_wait_for_track);
  }
  for (const std::string& method : s.pipeline.methods) {
    const pipeline::MethodName name = MethodOf(method);
    if (name.learned.empty() || method == "uavloc" || learned_.count(method)) continue;
    const std::string variant = VariantOfMethod(name.learned);
    const pipeline::UavLocModelFiles& files =
        variant == main.variant ? *model_ : *variant_models_.at(variant);
    learned_[method] = {name.modalities, files.LoadEdge(false)};
  }
  scripted_ = LoadScripted(s, scenario_file);
  for (const auto& [name, edge] : scripted_) {
    (void)edge;
    model_info_["scripted"][name] = s.pipeline.FindScripted(name)->edge;
  }
}

EdgeServer::~EdgeServer() = default;

bool EdgeServer::Runs(const std::string& method) const {
  const auto& methods = scenario_.pipeline.methods;
  return std::find(methods.begin(), methods.end(), method) != methods.end();
}

bool EdgeServer::SendsAnchors() const { return Runs("uavloc_anchored") || Runs("anchor_track"); }

const pipeline::NodeEncoder* EdgeServer::encoder(core::Modality m) const {
  return model_ ? &model_->encoder(m) : nullptr;
}

std::uint32_t EdgeServer::MessageBytes(core::Modality m) const {
  return channel::LatentMessageBytes(scenario_.pipeline.latent_dim) +
         (SendsAnchors() ? pipeline::AnchorBytes(m) : 0);
}

std::vector<std::string> EdgeServer::SteeredMethods() const {
  std::vector<std::string> steered;
  if (uavloc_) steered.push_back("uavloc");
  if (uavloc_anchored_) steered.push_back("uavloc_anchored");
  if (anchor_track_) steered.push_back("anchor_track");
  if (ekf_) steered.push_back("ekf");
  for (const auto& [method, learned] : learned_)
    if (learned.modalities == pipeline::kModalitySubsets) steered.push_back(method);
  for (const auto& [method, edge] : scripted_) steered.push_back(method);
  return steered;
}

bool EdgeServer::OnArrival(const channel::Message& m, core::SimTime t_arrival) {
  if (!receiver_.OnArrival(m, t_arrival) || !m.content) return false;
  const auto& content = *static_cast<const NodeContent*>(m.content.get());
  if (ekf_) {
    const auto timing = core::WallProfile::Measure(profile_, "edge/ekf");
    if (content.camera) ekf_->Observe(content.node_id, *content.camera);
    if (content.points) ekf_->Observe(content.node_id, *content.points);
  }
  const std::int64_t k = m.t_capture_ns / window_ns_ + 1;
  const int modality = static_cast<int>(m.modality);
  pipeline::GeometricAnchor anchor;
  if (SendsAnchors())
    anchor =
        content.camera ? pipeline::AnchorOf(*content.camera) : pipeline::AnchorOf(*content.points);
  if (model_ && !content.latent.empty()) {
    pipeline::WindowInputs& w = pending_[k];
    w.window = k;
    w.frames[modality].push_back({core::ToSeconds(m.t_capture_ns), content.latent, anchor});
  }
  if (anchor_track_ && anchor.kind != pipeline::GeometricAnchor::Kind::kNone)
    pending_anchors_[k][modality].push_back(anchor);
  return true;
}

std::map<std::string, Eigen::Vector3d> EdgeServer::EstimateWindow(std::int64_t tick, double t_s) {
  std::map<std::string, Eigen::Vector3d> estimated;
  const std::int64_t k = tick + 1;
  if (model_) {
    pipeline::WindowInputs inputs;
    inputs.window = k;
    if (auto it = pending_.find(k); it != pending_.end()) inputs = std::move(it->second);
    // Windows up to k are done (an arrival stamped exactly at a passed
    // deadline would otherwise linger).
    pending_.erase(pending_.begin(), pending_.upper_bound(k));
    for (auto& [method, learned] : learned_) {
      const auto timing = core::WallProfile::Measure(profile_, "edge/" + method);
      pipeline::WindowInputs fed;  // the modalities the method is fed
      fed.window = k;
      for (int m = 0; m < pipeline::kModalityCount; ++m)
        if (learned.modalities & (1 << m)) fed.frames[m] = inputs.frames[m];
      if (const auto p = learned.edge->OnWindow(fed)) estimated[method] = *p;
    }
    for (auto& [method, edge] : scripted_) {
      const auto timing = core::WallProfile::Measure(profile_, "edge/" + method);
      std::optional<Eigen::Vector3d> p;
      try {
        p = edge->OnWindow(inputs);
      } catch (const pipeline::ScriptedEdgeFailure& e) {
        throw pipeline::ScriptedEdgeFailure("method " + method + ": " + e.what(), e.traceback());
      }
      if (p) estimated[method] = *p;
    }
    if (uavloc_) {
      const auto timing = core::WallProfile::Measure(profile_, "edge/uavloc");
      if (const auto p = uavloc_->OnWindow(inputs)) estimated["uavloc"] = *p;
    }
    if (uavloc_anchored_) {
      const auto timing = core::WallProfile::Measure(profile_, "edge/uavloc_anchored");
      if (const auto p = uavloc_anchored_->OnWindow(inputs)) estimated["uavloc_anchored"] = *p;
    }
  }
  if (anchor_track_) {
    const auto timing = core::WallProfile::Measure(profile_, "edge/anchor_track");
    pipeline::WindowAnchors anchors;
    if (auto it = pending_anchors_.find(k); it != pending_anchors_.end())
      anchors = std::move(it->second);
    pending_anchors_.erase(pending_anchors_.begin(), pending_anchors_.upper_bound(k));
    if (const auto p = anchor_track_->OnWindow(k, anchors)) estimated["anchor_track"] = *p;
  }
  if (ekf_) {
    const auto timing = core::WallProfile::Measure(profile_, "edge/ekf");
    if (const auto p = ekf_->EstimateAt(t_s)) estimated["ekf"] = *p;
  }
  return estimated;
}

}  // namespace uavsim::sim
