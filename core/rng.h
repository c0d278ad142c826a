// Random streams. Every component draws from its own stream derived from
// (scenario seed, component id), so adding a sensor leaves every other
// stream unchanged (ns-3's AssignStreams, pbrt's Hash(p, seed)). There is no
// global generator. The generator (xoshiro256**) and the distributions are
// implemented here, not taken from <random>, so a seed gives the same numbers
// with any standard library.
#pragma once

#include <cstdint>
#include <string_view>

namespace uavsim::core {

// 64-bit FNV-1a of a string; stable across platforms.
std::uint64_t HashString(std::string_view s);
// SplitMix64 finaliser: a bijective mix of 64 bits.
std::uint64_t Mix64(std::uint64_t x);

class RngStream {
 public:
  // The stream of component `component_id` under scenario seed `seed`.
  RngStream(std::uint64_t seed, std::string_view component_id);
  // A stream from a raw 64-bit key (for sub-streams: Derive).
  explicit RngStream(std::uint64_t key);

  // An independent child stream, e.g. per trajectory or per frame.
  RngStream Derive(std::string_view sub_id) const;

  std::uint64_t NextU64();
  double Uniform();                           // [0, 1), 53 random bits
  double Uniform(double lo, double hi);       // [lo, hi)
  std::uint64_t UniformInt(std::uint64_t n);  // [0, n), unbiased; n > 0
  double Normal();                            // standard normal (Marsaglia polar)
  double Normal(double mean, double stddev);
  double Exponential(double mean);
  double Pareto(double scale, double shape);  // x >= scale, P(X > x) = (scale/x)^shape
  bool Bernoulli(double p);

  std::uint64_t key() const { return key_; }

 private:
  std::uint64_t key_;
  std::uint64_t s_[4];
  double spare_normal_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace uavsim::core
