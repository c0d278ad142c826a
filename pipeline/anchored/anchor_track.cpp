#include "pipeline/anchored/anchor_track.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace uavsim::pipeline {

AnchorTrack::AnchorTrack(double window_s) : window_s_(window_s) {
  if (!(window_s > 0.0) || !std::isfinite(window_s))
    throw std::invalid_argument("AnchorTrack: window_s must be finite and > 0");
}

void AnchorTrack::Reset() {
  filter_.Reset();
  last_window_.reset();
  last_.reset();
}

std::optional<Eigen::Vector3d> AnchorTrack::OnWindow(std::int64_t k, const WindowAnchors& arrived) {
  if (last_window_ && k <= *last_window_)
    throw std::invalid_argument("AnchorTrack::OnWindow: window " + std::to_string(k) +
                                " is not after window " + std::to_string(*last_window_));
  last_window_ = k;
  filter_.ObserveWindow(arrived);  // as AnchorTracker::Update feeds its filter

  const std::optional<AnchorFilter::Estimate> track =
      filter_.PredictAt(static_cast<double>(k) * window_s_);
  if (track && (last_ || track->sigma_m <= kConfirmedSigma_m)) last_ = track->position_m;
  return last_;
}

}  // namespace uavsim::pipeline
