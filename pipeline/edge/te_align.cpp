#include "pipeline/edge/te_align.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/json_io.h"

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

const std::vector<std::pair<const char*, Alignment>>& AlignmentNames() {
  static const std::vector<std::pair<const char*, Alignment>> names = {
      {"te_align", Alignment::kTeAlign},
      {"first", Alignment::kFirst},
      {"middle", Alignment::kMiddle},
      {"random", Alignment::kRandom}};
  return names;
}

const char* AlignmentName(Alignment a) {
  for (const auto& [name, value] : AlignmentNames())
    if (value == a) return name;
  return "?";
}

std::size_t RandomFrameIndex(std::int64_t k, int m, std::size_t n) {
  if (n == 0) throw std::invalid_argument("RandomFrameIndex: no frame to pick from");
  // SplitMix64 of (k, m): a fixed, well-mixed draw per window and modality.
  std::uint64_t x =
      static_cast<std::uint64_t>(k) * 4 + static_cast<std::uint64_t>(m) + 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  x ^= x >> 31;
  return static_cast<std::size_t>(x % n);
}

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
    std::vector<const LatentFrame*> in_window;
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
      in_window.push_back(&frame);
    }
    std::vector<float>& pooled = out.latent[static_cast<std::size_t>(m)];
    pooled.assign(z, 0.0f);
    out.mask[static_cast<std::size_t>(m)] = in_window.empty() ? 0.0f : 1.0f;
    if (in_window.empty()) continue;
    if (config_.alignment != Alignment::kTeAlign) {
      // Sec. VI, Fig. 12: one frame of the window, as it is.
      std::stable_sort(in_window.begin(), in_window.end(),
                       [](const LatentFrame* a, const LatentFrame* b) { return a->t_s < b->t_s; });
      const std::size_t n = in_window.size();
      const std::size_t i = config_.alignment == Alignment::kFirst ? 0
                            : config_.alignment == Alignment::kMiddle
                                ? n / 2
                                : RandomFrameIndex(window.window, m, n);
      pooled = in_window[i]->latent;
      continue;
    }
    std::vector<double> sum(z, 0.0);
    for (const LatentFrame* frame : in_window) {
      const std::vector<double> e = Encoding(Tau(frame->t_s, window.window));  // Eq. (19)
      for (std::size_t j = 0; j < z; ++j) sum[j] += static_cast<double>(frame->latent[j]) + e[j];
    }
    const double count = static_cast<double>(in_window.size());  // Eq. (20)
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
