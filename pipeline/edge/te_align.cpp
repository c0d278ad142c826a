#include "pipeline/edge/te_align.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "sim/core/json_io.h"

namespace uavsim::pipeline {
namespace {

using core::FormatNumber;

constexpr double kNsPerS = 1e9;
// 9e9 s in ns stays below 2^63 with room for the window arithmetic.
constexpr double kMaxAbsTime_s = 9e9;

// Floor division: window indices must also be right for negative times.
std::int64_t FloorDiv(std::int64_t a, std::int64_t b) {
  std::int64_t q = a / b;
  if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
  return q;
}

}  // namespace

void TeAlignConfig::Validate() const {
  if (latent_dim < 2 || latent_dim % 2 != 0 || latent_dim > 4096)
    throw std::invalid_argument("TeAlign: latent_dim (" + std::to_string(latent_dim) +
                                ") must be an even integer in [2, 4096]");
  if (!std::isfinite(window_s) || window_s < 1e-9 || window_s > 3600.0)
    throw std::invalid_argument("TeAlign: window_s (" + FormatNumber(window_s) +
                                ") must be a finite number of seconds in [1e-9, 3600]");
  if (!std::isfinite(kappa) || kappa <= 1.0)
    throw std::invalid_argument("TeAlign: kappa (" + FormatNumber(kappa) +
                                ") must be finite and > 1");
  if (!std::isfinite(time_unit_s) || time_unit_s <= 0.0)
    throw std::invalid_argument("TeAlign: time_unit_s (" + FormatNumber(time_unit_s) +
                                ") must be finite and > 0");
}

TeAlign::TeAlign(const TeAlignConfig& config) : config_(config) {
  config_.Validate();
  window_ns_ = std::llround(config_.window_s * kNsPerS);
  const int half = config_.latent_dim / 2;
  inv_frequency_.resize(static_cast<std::size_t>(half));
  for (int j = 1; j <= half; ++j)
    inv_frequency_[static_cast<std::size_t>(j - 1)] =
        std::pow(config_.kappa, -2.0 * j / config_.latent_dim);
}

std::int64_t TeAlign::WindowOf(double t_s) const {
  if (!std::isfinite(t_s) || std::abs(t_s) > kMaxAbsTime_s)
    throw std::invalid_argument("TeAlign: time stamp " + FormatNumber(t_s) +
                                " s is not finite or beyond 9e9 s");
  const std::int64_t t_ns = std::llround(t_s * kNsPerS);
  return FloorDiv(t_ns, window_ns_) + 1;
}

double TeAlign::WindowStart_s(std::int64_t k) const {
  return static_cast<double>((k - 1) * window_ns_) / kNsPerS;
}

double TeAlign::Tau(double t_s, std::int64_t k) const {
  // From integer nanoseconds, so the offset is exact to the clock's tick and
  // never a rounding error of a large absolute time.
  const std::int64_t t_ns = std::llround(t_s * kNsPerS);
  const std::int64_t origin_ns =
      config_.tau_origin == TauOrigin::kWindow ? (k - 1) * window_ns_ : 0;
  const std::int64_t offset_ns = t_ns - origin_ns;
  return static_cast<double>(offset_ns) / kNsPerS / config_.time_unit_s;
}

std::vector<double> TeAlign::Encoding(double tau) const {
  std::vector<double> e(static_cast<std::size_t>(config_.latent_dim));
  for (std::size_t j = 0; j < inv_frequency_.size(); ++j) {
    const double angle = tau * inv_frequency_[j];
    e[2 * j] = std::sin(angle);
    e[2 * j + 1] = std::cos(angle);
  }
  return e;
}

AlignedWindow TeAlign::Align(const WindowInputs& window) const {
  const std::size_t z = static_cast<std::size_t>(config_.latent_dim);
  AlignedWindow out;
  out.window = window.window;
  for (int m = 0; m < kModalityCount; ++m) {
    std::vector<double> sum(z, 0.0);
    int count = 0;
    for (const LatentFrame& frame : window.frames[static_cast<std::size_t>(m)]) {
      if (frame.latent.size() != z)
        throw std::invalid_argument("TeAlign: latent of modality " + std::to_string(m) + " has " +
                                    std::to_string(frame.latent.size()) +
                                    " values, expected z = " + std::to_string(z));
      for (float v : frame.latent)
        if (!std::isfinite(v))
          throw std::invalid_argument("TeAlign: latent of modality " + std::to_string(m) +
                                      " holds a non-finite value");
      if (WindowOf(frame.t_s) != window.window) {
        ++out.frames_outside_window;
        continue;
      }
      const std::vector<double> e = Encoding(Tau(frame.t_s, window.window));
      for (std::size_t j = 0; j < z; ++j) sum[j] += static_cast<double>(frame.latent[j]) + e[j];
      ++count;
    }
    std::vector<float>& pooled = out.latent[static_cast<std::size_t>(m)];
    pooled.assign(z, 0.0f);
    out.mask[static_cast<std::size_t>(m)] = count > 0 ? 1.0f : 0.0f;
    if (count == 0) continue;
    for (std::size_t j = 0; j < z; ++j) pooled[j] = static_cast<float>(sum[j] / count);
  }
  return out;
}

WindowAnchors TeAlign::AnchorsOf(const WindowInputs& window) const {
  WindowAnchors out;
  for (std::size_t m = 0; m < out.size(); ++m) {
    std::vector<const LatentFrame*> frames;
    for (const LatentFrame& frame : window.frames[m])
      if (frame.anchor.kind != GeometricAnchor::Kind::kNone && WindowOf(frame.t_s) == window.window)
        frames.push_back(&frame);
    std::stable_sort(frames.begin(), frames.end(),
                     [](const LatentFrame* a, const LatentFrame* b) { return a->t_s < b->t_s; });
    for (const LatentFrame* frame : frames) out[m].push_back(frame->anchor);
  }
  return out;
}

}  // namespace uavsim::pipeline
