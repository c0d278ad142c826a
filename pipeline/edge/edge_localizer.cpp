#include "pipeline/edge/edge_localizer.h"

#include <utility>

#include "pipeline/edge/uavloc_model.h"

namespace uavsim::pipeline {

struct EdgeLocalizer::Impl {
  explicit Impl(UavLocModel m) : model(std::move(m)) {}
  UavLocModel model;
  bool has_seen_data = false;
  bool wait_for_track = false;
  bool has_seen_track = false;
  std::optional<std::int64_t> last_window;
};

EdgeLocalizer::EdgeLocalizer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
EdgeLocalizer::~EdgeLocalizer() = default;

std::unique_ptr<EdgeLocalizer> EdgeLocalizer::Load(const std::string& path) {
  UavLocModel model = LoadUavLocModel(path);
  model->eval();
  return std::unique_ptr<EdgeLocalizer>(
      new EdgeLocalizer(std::make_unique<Impl>(std::move(model))));
}

std::unique_ptr<EdgeLocalizer> EdgeLocalizer::Create(int latent_dim, double window_s,
                                                     bool anchored) {
  UavLocModelConfig config;
  config.latent_dim = latent_dim;
  config.window_s = window_s;
  config.anchored = anchored;
  UavLocModel model(config);
  model->eval();
  return std::unique_ptr<EdgeLocalizer>(
      new EdgeLocalizer(std::make_unique<Impl>(std::move(model))));
}

std::optional<Eigen::Vector3d> EdgeLocalizer::OnWindow(const WindowInputs& window) {
  const Eigen::Vector3d p = impl_->model->Step(window);
  // A gap the model cannot step through restarts it from a zero state: it
  // has then seen nothing again.
  if (impl_->last_window &&
      window.window - *impl_->last_window > UavLocModelImpl::kMaxGapWindows + 1)
    impl_->has_seen_data = impl_->has_seen_track = false;
  impl_->last_window = window.window;
  const TeAlign& align = impl_->model->te_align();
  for (const auto& frames : window.frames)
    for (const LatentFrame& f : frames)
      if (align.WindowOf(f.t_s) == window.window) impl_->has_seen_data = true;
  const AnchorWindow& anchors = impl_->model->last_anchors();
  if (anchored() && anchors.valid[static_cast<std::size_t>(kFilterCandidate)] > 0.5f &&
      anchors.features[static_cast<std::size_t>(kFilterSigmaFeature)] *
              AnchorTracker::kSigmaUnit_m <=
          kConfirmedSigma_m)
    impl_->has_seen_track = true;
  if (!impl_->has_seen_data || !p.allFinite()) return std::nullopt;
  if (impl_->wait_for_track && anchored() && !impl_->has_seen_track) return std::nullopt;
  return p;
}

void EdgeLocalizer::WaitForTrack(bool wait) { impl_->wait_for_track = wait; }

void EdgeLocalizer::Reset() {
  impl_->model->ResetState();
  impl_->has_seen_data = impl_->has_seen_track = false;
  impl_->last_window.reset();
}

int EdgeLocalizer::latent_dim() const { return impl_->model->config().latent_dim; }
double EdgeLocalizer::window_s() const { return impl_->model->config().window_s; }
bool EdgeLocalizer::anchored() const { return impl_->model->config().anchored; }

}  // namespace uavsim::pipeline
