#include "sim/edge_server.h"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <set>

#include "core/sha256.h"
#include "pipeline/anchored/geometric_anchor.h"
#include "pipeline/model_checksums.h"
#include "pipeline/torch_runtime.h"

namespace uavsim::sim {
namespace {

bool Runs(const Scenario& s, const std::string& method) {
  const auto& methods = s.pipeline.methods;
  return std::find(methods.begin(), methods.end(), method) != methods.end();
}

// The scenario's methods in the order the downlink scores them (rate_snr.csv
// and the report): uavloc, uavloc_anchored, anchor_track, ekf, then the
// other learned methods, the TorchScript ones and the Python ones, each by
// name.
std::vector<std::string> MethodOrder(const Scenario& s) {
  std::vector<std::string> order;
  for (const char* fixed :
       {"uavloc", "uavloc_anchored", "anchor_track", "ekf", "mtt", "mtt_jpda", "uavloc_per_track"})
    if (Runs(s, fixed)) order.push_back(fixed);
  std::set<std::string> learned, scripted, hosted;
  for (const std::string& method : s.pipeline.methods) {
    if (s.pipeline.FindScripted(method))
      scripted.insert(method);
    else if (s.pipeline.FindHosted(method))
      hosted.insert(method);
    else if (std::find(order.begin(), order.end(), method) == order.end())
      learned.insert(method);
  }
  order.insert(order.end(), learned.begin(), learned.end());
  order.insert(order.end(), scripted.begin(), scripted.end());
  order.insert(order.end(), hosted.begin(), hosted.end());
  return order;
}

std::vector<std::unique_ptr<pipeline::LocalizationMethod>> MakeMethods(
    const Scenario& s, pipeline::ModelCatalog& catalog, const HostedMethods* hosted) {
  std::vector<std::unique_ptr<pipeline::LocalizationMethod>> methods;
  for (const std::string& name : MethodOrder(s)) {
    if (const pipeline::HostedMethod* entry = s.pipeline.FindHosted(name))
      methods.push_back(hosted->at(name)(*entry, s.pipeline.latent_dim, s.pipeline.window_s));
    else if (name == "ekf")
      methods.push_back(pipeline::MakeEkfMethod(MakeEkf(s)));
    else if (name == "anchor_track")
      methods.push_back(pipeline::MakeAnchorTrackMethod(s.pipeline.window_s));
    else if (name == "mtt" || name == "mtt_jpda")
      methods.push_back(pipeline::MakeMttMethod(s.pipeline.window_s, name == "mtt_jpda"));
    else if (auto method = catalog.MakeMethod(name))
      methods.push_back(std::move(method));
  }
  return methods;
}

}  // namespace

std::unique_ptr<pipeline::Ekf> MakeEkf(const Scenario& s) {
  pipeline::EkfConfig config = s.pipeline.ekf;
  const UavConfig& target = s.uavs[FirstTarget(s)];
  config.max_speed_mps = target.trajectory.max_speed_mps;
  config.max_accel_mps2 = target.trajectory.max_accel_mps2;
  config.target_size_m = target.size_m;
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

namespace {

std::string FingerprintOf(const pipeline::ModelCatalog& catalog) {
  namespace fs = std::filesystem;
  if (!catalog.needs_model()) return "none";
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(fs::path(catalog.model_path()).parent_path()))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::string list;
  for (const fs::path& f : files)
    list += f.filename().string() + " " + core::Sha256FileHex(f.string()) + "\n";
  return core::Sha256Hex(list);
}

}  // namespace

std::string EncoderFingerprint(const Scenario& s, const std::string& file) {
  return FingerprintOf(pipeline::ModelCatalog(CatalogOf(s, file)));
}

std::string EdgeServer::encoder_fingerprint() const {
  return catalog_ ? FingerprintOf(*catalog_) : "none";
}

void CheckTrainedModel(const Scenario& s, const std::string& file, bool quiet,
                       const HostedMethods* hosted) {
  if (!CheckModelFiles(s, file, hosted)) return;
  pipeline::InitTorch(1, s.seed);
  pipeline::ModelCatalog catalog(CatalogOf(s, file));
  catalog.LoadScripted();
  if (catalog.unchecked().empty()) return;
  // Nothing vouches for such a folder's files (a truncated radar.pt passed
  // validate once): they are checked as the run reads them, by loading
  // every one the run loads.
  { const EdgeServer loaded(s, file, /*quiet=*/true, /*methods=*/true, hosted); }
  if (!quiet)
    for (const std::string& p : catalog.unchecked())
      std::cerr << file << ": /pipeline/model: warning: " << p << ": its folder has no "
                << pipeline::kModelChecksumsFile
                << " (a model from before they were kept): checked by loading it\n";
}

std::string CheckEncoderModel(const Scenario& s, const std::string& file, const std::string& dir,
                              const std::string& command) {
  return pipeline::ResolveEncoderModel(CatalogOf(s, file), dir, command);
}

EdgeServer::EdgeServer(const Scenario& s, const std::string& scenario_file, bool quiet,
                       bool methods, const HostedMethods* hosted)
    : scenario_(s),
      receiver_(s.pipeline.window_s, s.pipeline.late_allowance_s),
      window_ns_(core::Seconds(s.pipeline.window_s)) {
  if (!methods) return;
  CheckHostedMethods(s, scenario_file, hosted);
  catalog_ = std::make_unique<pipeline::ModelCatalog>(CatalogOf(s, scenario_file));
  if (catalog_->needs_model()) {
    pipeline::InitTorch(1, s.seed);
    catalog_->Load(quiet);
  }
  methods_ = MakeMethods(s, *catalog_, HostedOrProcess(hosted));
  for (const auto& m : methods_) {
    needs_.arrivals |= m->needs().arrivals;
    needs_.latents |= m->needs().latents;
    needs_.anchors |= m->needs().anchors;
    needs_.detections |= m->needs().detections;
  }
}

EdgeServer::~EdgeServer() = default;

const core::Json& EdgeServer::model_info() const {
  static const core::Json none;
  return catalog_ ? catalog_->info() : none;
}

const pipeline::NodeEncoder* EdgeServer::encoder(core::Modality m) const {
  return catalog_ ? catalog_->encoder(m) : nullptr;
}

std::uint32_t EdgeServer::MessageBytes(core::Modality m) const {
  return channel::LatentMessageBytes(scenario_.pipeline.latent_dim) +
         (pipeline::SendsAnchors(scenario_.pipeline) ? pipeline::AnchorBytes(m) : 0);
}

std::vector<std::string> EdgeServer::SteeredMethods() const {
  std::vector<std::string> steered;
  for (const auto& m : methods_)
    if (m->steers_beam()) steered.push_back(m->name());
  return steered;
}

bool EdgeServer::OnArrival(const channel::Message& m, core::SimTime t_arrival) {
  if (!receiver_.OnArrival(m, t_arrival) || !m.content) return false;
  const auto& content = ContentOf(m);
  const double t_capture_s = core::ToSeconds(m.t_capture_ns);
  if (needs_.arrivals) {
    const pipeline::Arrival arrival{&content.node_id, m.modality, t_capture_s,
                                    content.camera ? &*content.camera : nullptr,
                                    content.points ? &*content.points : nullptr};
    for (const auto& method : methods_) {
      if (!method->needs().arrivals) continue;
      const auto timing = core::WallProfile::Measure(profile_, "edge/" + method->name());
      method->Observe(arrival);
    }
  }
  const std::int64_t k = m.t_capture_ns / window_ns_ + 1;
  const int modality = static_cast<int>(m.modality);
  pipeline::GeometricAnchor anchor;
  if (needs_.anchors)
    anchor =
        content.camera ? pipeline::AnchorOf(*content.camera) : pipeline::AnchorOf(*content.points);
  if (needs_.latents && !content.latent.empty()) {
    pipeline::WindowInputs& w = pending_[k].latents;
    w.window = k;
    w.frames[modality].push_back({t_capture_s, content.latent, anchor});
  }
  if (needs_.anchors && anchor.kind != pipeline::GeometricAnchor::Kind::kNone)
    pending_[k].anchors[modality].push_back(anchor);
  if (needs_.detections) AddDetections(k, m, content);
  if (keep_arrivals_)
    pending_records_[k].push_back({content.node_id, m.modality, t_capture_s, content.latent,
                                   content.camera ? pipeline::AnchorOf(*content.camera)
                                                  : pipeline::AnchorOf(*content.points)});
  return true;
}

void EdgeServer::AddDetections(std::int64_t k, const channel::Message& m,
                               const NodeContent& content) {
  std::vector<pipeline::Detection>& out = pending_[k].detections;
  const auto add = [&](const NodeObservation& o) {
    if (!o.Found()) return;
    pipeline::Detection d;
    d.modality = m.modality;
    d.node = m.node;
    d.t_capture_s = core::ToSeconds(m.t_capture_ns);
    d.anchor = o.camera ? pipeline::AnchorOf(*o.camera) : pipeline::AnchorOf(*o.points);
    d.latent = o.latent;
    if (d.anchor.kind != pipeline::GeometricAnchor::Kind::kNone) out.push_back(std::move(d));
  };
  add(content);
  for (const NodeObservation& o : content.further) add(o);
}

std::map<std::string, Eigen::Vector3d> EdgeServer::EstimateWindow(std::int64_t tick, double t_s) {
  const std::int64_t k = tick + 1;
  pipeline::WindowArrivals w;
  if (auto it = pending_.find(k); it != pending_.end()) w = std::move(it->second);
  // Windows up to k are done (an arrival stamped exactly at a passed
  // deadline would otherwise linger).
  pending_.erase(pending_.begin(), pending_.upper_bound(k));
  if (keep_arrivals_) {
    last_arrivals_.clear();
    if (auto it = pending_records_.find(k); it != pending_records_.end())
      last_arrivals_ = std::move(it->second);
    pending_records_.erase(pending_records_.begin(), pending_records_.upper_bound(k));
  }
  w.k = k;
  w.t_end_s = t_s;
  w.latents.window = k;
  std::map<std::string, Eigen::Vector3d> estimated;
  last_tracks_.clear();
  for (const auto& method : methods_) {
    const auto timing = core::WallProfile::Measure(profile_, "edge/" + method->name());
    if (const auto p = method->Estimate(w)) estimated[method->name()] = *p;
    if (auto tracks = method->Tracks()) last_tracks_[method->name()] = std::move(*tracks);
  }
  return estimated;
}

}  // namespace uavsim::sim
