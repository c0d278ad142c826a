#include "pipeline/edge/latent_history.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace uavsim::pipeline {
namespace {
constexpr std::size_t M = kModalityCount;
}  // namespace

LatentHistory::LatentHistory(int history_windows, int latent_dim, double window_s)
    : history_(history_windows), latent_dim_(latent_dim), window_s_(window_s) {
  if (history_windows < 1 || latent_dim < 1 || !(window_s > 0.0))
    throw std::invalid_argument("LatentHistory: history_windows and latent_dim >= 1, window_s > 0");
}

void LatentHistory::Push(const WindowInputs& window) {
  if (last_window_ && window.window <= *last_window_)
    throw std::invalid_argument("window " + std::to_string(window.window) +
                                " does not come after " + std::to_string(*last_window_));
  for (const auto& frames : window.frames)
    for (const LatentFrame& f : frames) {
      if (static_cast<int>(f.latent.size()) != latent_dim_)
        throw std::invalid_argument("a latent of " + std::to_string(f.latent.size()) +
                                    " values, expected " + std::to_string(latent_dim_));
      has_seen_data_ = true;
    }
  // Skipped windows are empty ones.
  const std::int64_t from = last_window_ ? *last_window_ + 1 : window.window;
  for (std::int64_t k = std::max(from, window.window - history_ + 1); k < window.window; ++k) {
    WindowInputs empty;
    empty.window = k;
    windows_.push_back(std::move(empty));
  }
  windows_.push_back(window);
  while (static_cast<int>(windows_.size()) > history_) windows_.pop_front();
  last_window_ = window.window;
}

PackedWindows LatentHistory::Pack() const {
  std::size_t frames = 1;
  for (const WindowInputs& w : windows_)
    for (const auto& f : w.frames) frames = std::max(frames, f.size());
  PackedWindows p;
  p.windows = history_;
  p.frames = static_cast<int>(frames);
  p.latent_dim = latent_dim_;
  const std::size_t L = static_cast<std::size_t>(history_), F = frames,
                    z = static_cast<std::size_t>(latent_dim_);
  p.latents.assign(L * M * F * z, 0.0f);
  p.offsets_s.assign(L * M * F, 0.0f);
  p.mask.assign(L * M * F, 0.0f);
  const std::size_t first = L - windows_.size();
  for (std::size_t i = 0; i < windows_.size(); ++i) {
    const WindowInputs& w = windows_[i];
    const std::size_t l = first + i;
    const double start_s = static_cast<double>(w.window - 1) * window_s_;
    for (std::size_t m = 0; m < M; ++m) {
      std::vector<const LatentFrame*> sorted;
      for (const LatentFrame& f : w.frames[m]) sorted.push_back(&f);
      std::stable_sort(sorted.begin(), sorted.end(),
                       [](const LatentFrame* a, const LatentFrame* b) { return a->t_s < b->t_s; });
      for (std::size_t f = 0; f < sorted.size(); ++f) {
        const std::size_t cell = (l * M + m) * F + f;
        std::copy(sorted[f]->latent.begin(), sorted[f]->latent.end(),
                  p.latents.begin() + static_cast<std::ptrdiff_t>(cell * z));
        p.offsets_s[cell] = static_cast<float>(sorted[f]->t_s - start_s);
        p.mask[cell] = 1.0f;
      }
    }
  }
  return p;
}

}  // namespace uavsim::pipeline
