// TE-Align, the edge server's time-encoding alignment (paper Sec. V-A): each
// latent frame t_i^m gets a sinusoidal encoding of its time stamp added, then
// the frames of one modality that fall in the same window of t^w seconds are
// average-pooled. Plain C++ (no LibTorch): it has no learned parameters, and
// the engine, the training-data code and the online step all share it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "pipeline/anchored/geometric_anchor.h"
#include "pipeline/node/observations.h"

namespace uavsim::pipeline {

// Where τ_i^m of Eq. (19) is measured from.
enum class TauOrigin {
  kWindow,  // the start of the frame's window (ours, the default)
  kClock,   // the simulated clock's zero, the run's (an episode's) start: the
            // paper's "timestamp of the i-th data frame"
};

// How a window's frames of one modality become one vector: TE-Align (the
// paper's, Eqs. (19)-(20)) or one of the resampling baselines it is compared
// against (Sec. VI, Fig. 12), which keep one frame's latent as it is (no time
// encoding): the first, the middle or a random one of the modality's frames
// stamped in the window, in time-stamp order. The middle of n frames is the
// one at index floor(n / 2) (0-based: the later of the two middle ones when n
// is even). The random pick is a hash of (window k, modality, n), the same in
// every run, in training and in the loop (SplitMix64: RandomFrameIndex).
enum class Alignment { kTeAlign, kFirst, kMiddle, kRandom };

// The names in configuration files: "te_align", "first", "middle", "random".
const std::vector<std::pair<const char*, Alignment>>& AlignmentNames();
const char* AlignmentName(Alignment a);

// The index in [0, n) RandomFrameIndex picks for window k and modality m
// (n >= 1).
std::size_t RandomFrameIndex(std::int64_t k, int m, std::size_t n);

struct TeAlignConfig {
  int latent_dim = 16;     // z^m, the same for every modality; even (paper: 4 ... 64)
  double window_s = 0.2;   // t^w (paper Sec. VI)
  double kappa = 10000.0;  // κ of the encoding
  // τ_i^m is the frame's offset into its window, in these units (1e-3: ms).
  // The paper fixes neither origin nor unit of τ: an absolute clock in seconds
  // makes the encoding a slowly drifting offset tied to a run's start time
  // (its fastest channel has a period of 20 s at z = 16), while the offset in
  // milliseconds spans the window as transformer positions span a sequence.
  double time_unit_s = 1e-3;
  // The paper's τ is the frame's time stamp (kClock); ours its offset into the
  // window (kWindow), so a window's encoding does not depend on how long the
  // run has gone (measured: docs/training.md, "The paper's design and ours").
  TauOrigin tau_origin = TauOrigin::kWindow;
  // TE-Align or a resampling baseline (see Alignment).
  Alignment alignment = Alignment::kTeAlign;

  // Throws std::invalid_argument naming the field, its value and the rule.
  void Validate() const;
};

// One latent packet as the edge received it: the node's capture time stamp on
// the common simulated clock (paper Sec. III assumption (i)) and t_i^m.
struct LatentFrame {
  double t_s = 0.0;
  std::vector<float> latent;  // size z
  // Where the node's pre-processing put the target (an anchored model's
  // input; TE-Align ignores it).
  GeometricAnchor anchor;
};

// Everything that arrived for window k, per modality (index: Modality).
struct WindowInputs {
  std::int64_t window = 1;  // k; the window covers (k-1) t^w <= t_s < k t^w
  std::array<std::vector<LatentFrame>, kModalityCount> frames;
};

// t^{m,e}(k) and mask^m(k) of one window.
struct AlignedWindow {
  std::int64_t window = 1;
  std::array<std::vector<float>, kModalityCount> latent;  // size z each; zeros when missing
  std::array<float, kModalityCount> mask{};               // 1: available, 0: missing
  int frames_outside_window = 0;  // frames of the input that lie in another window (ignored)
};

class TeAlign {
 public:
  // Validates `config` (throws std::invalid_argument).
  explicit TeAlign(const TeAlignConfig& config);

  // k of the window holding time stamp t_s: (k-1) t^w <= t_s < k t^w, so the
  // first window (k = 1) starts at t = 0. Time stamps are rounded to the
  // simulator's integer nanoseconds first, so a frame stamped exactly on a
  // boundary opens the next window whatever the binary rounding of t_s.
  // Throws std::invalid_argument for a non-finite t_s or |t_s| > 9e9 s.
  std::int64_t WindowOf(double t_s) const;
  double WindowStart_s(std::int64_t k) const;  // (k-1) t^w

  // τ of a frame stamped t_s in window k, in units of time_unit_s: from the
  // window's start or from the clock's zero (tau_origin).
  double Tau(double t_s, std::int64_t k) const;

  // Eq. (19): E^m_i = [sin(τ/κ^{2j/z}), cos(τ/κ^{2j/z})]_{j=1..z/2}.
  // Interleaved: element 2(j-1) is the sine and 2j-1 the cosine of channel j.
  std::vector<double> Encoding(double tau) const;

  // Eq. (20): t^{m,e}(k) = mean over i in s^m(k) of t_i^m + E_i^m.
  // Pools the frames of window.window, mask 1; a modality with no frame in
  // the window gets a zero vector and mask 0. With a resampling `alignment`
  // the chosen frame's latent instead (no encoding). Frames stamped in another window
  // are ignored and counted. Throws std::invalid_argument if a latent's size
  // is not z or it holds a non-finite value.
  AlignedWindow Align(const WindowInputs& window) const;
  // Per modality the anchors of the frames stamped in the window, in capture
  // order.
  WindowAnchors AnchorsOf(const WindowInputs& window) const;

  const TeAlignConfig& config() const { return config_; }

 private:
  TeAlignConfig config_;
  std::int64_t window_ns_;
  std::vector<double> inv_frequency_;  // 1/κ^{2j/z}, j = 1..z/2
};

}  // namespace uavsim::pipeline
