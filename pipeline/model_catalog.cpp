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

// The model's temporal regressor ("mamba", the paper's, or one of its
// baselines); models without a recorded config predate the choice: "mamba".
const char* TemporalOf(const ModelManifest& m) {
  return TemporalKindName(m.training ? m.training->temporal : TemporalKind::kMamba);
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

ModelCatalog::ModelCatalog(CatalogScenario s) : s_(std::move(s)), resolved_(ResolveModels(s_)) {}

ModelCatalog::~ModelCatalog() = default;
ModelCatalog::ModelCatalog(ModelCatalog&&) noexcept = default;

void ModelCatalog::LoadScripted() {
  if (scripted_.empty()) scripted_ = LoadScriptedEdges(s_, s_.file);
}

void ModelCatalog::Load(bool quiet) {
  if (!resolved_.needs_model || model_) return;
  try {
    model_ = UavLocModelFiles::Load(resolved_.model_path);
  } catch (const core::ConfigError& e) {
    throw core::ConfigError(s_.file, "/pipeline/model",
                            std::string(e.what()) + " (" + kHowToTrain + ")");
  }
  const ModelManifest& m = model_->manifest();
  const bool same_layout = m.layout_hash == s_.layout_hash;
  if (!same_layout && !quiet)
    std::cerr << "uavsim: warning: the model " << resolved_.model_path
              << " was trained for scenario \"" << m.scenario
              << "\" with another world or node layout; its estimates may be poor (" << kHowToTrain
              << ")\n";
  core::Json heads = core::Json::array();
  if (!model_->heads().paper.empty()) heads.push_back("paper");
  if (!model_->heads().anchored.empty()) heads.push_back("anchored");
  info_ = {{"path", resolved_.model_path},
           {"trained_for", m.scenario},
           {"same_layout", same_layout},
           {"heads", heads},
           {"extensions", ExtensionsOf(m)}};
  if (info_["extensions"].is_array())
    for (const std::string& e : NodeExtensions(s_.pipeline->preprocess))
      info_["extensions"].push_back(e);
  const auto& methods = s_.pipeline->methods;
  if (info_["extensions"].is_array() &&
      std::find(methods.begin(), methods.end(), "uavloc_per_track") != methods.end())
    info_["extensions"].push_back("method=uavloc_per_track");
  info_["temporal"] = TemporalOf(m);
  info_["variant"] = m.variant;
  for (const auto& [variant, path] : resolved_.variant_paths) {
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
  const MethodName method = ParseMethod(name).value_or(MethodName{});
  if (method.learned.empty()) return nullptr;
  const std::string variant = VariantOfMethod(method.learned);
  const UavLocModelFiles& files =
      variant == resolved_.manifest.variant ? *model_ : *variant_models_.at(variant);
  return MakeLearnedMethod(name, files.LoadEdge(false), method.modalities, /*anchored=*/false);
}

}  // namespace uavsim::pipeline
