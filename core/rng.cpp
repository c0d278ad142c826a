#include "core/rng.h"

#include <cmath>

namespace uavsim::core {

std::uint64_t HashString(std::string_view s) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : s) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::uint64_t Mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

RngStream::RngStream(std::uint64_t seed, std::string_view component_id)
    : RngStream(Mix64(Mix64(seed) ^ HashString(component_id))) {}

RngStream::RngStream(std::uint64_t key) : key_(key) {
  std::uint64_t x = key;
  for (auto& s : s_) {  // SplitMix64 seeding, as the xoshiro authors recommend
    x += 0x9e3779b97f4a7c15ULL;
    s = Mix64(x - 0x9e3779b97f4a7c15ULL);
  }
}

RngStream RngStream::Derive(std::string_view sub_id) const {
  return RngStream(Mix64(key_ ^ Mix64(HashString(sub_id))));
}

static inline std::uint64_t Rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

std::uint64_t RngStream::NextU64() {  // xoshiro256** 1.0
  const std::uint64_t result = Rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = Rotl(s_[3], 45);
  return result;
}

double RngStream::Uniform() { return static_cast<double>(NextU64() >> 11) * 0x1.0p-53; }

double RngStream::Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }

std::uint64_t RngStream::UniformInt(std::uint64_t n) {
  // Lemire's nearly divisionless method.
  __uint128_t m = static_cast<__uint128_t>(NextU64()) * n;
  auto low = static_cast<std::uint64_t>(m);
  if (low < n) {
    const std::uint64_t threshold = -n % n;
    while (low < threshold) {
      m = static_cast<__uint128_t>(NextU64()) * n;
      low = static_cast<std::uint64_t>(m);
    }
  }
  return static_cast<std::uint64_t>(m >> 64);
}

double RngStream::Normal() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_normal_;
  }
  double u, v, s;
  do {
    u = 2.0 * Uniform() - 1.0;
    v = 2.0 * Uniform() - 1.0;
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  const double f = std::sqrt(-2.0 * std::log(s) / s);
  spare_normal_ = v * f;
  has_spare_ = true;
  return u * f;
}

double RngStream::Normal(double mean, double stddev) { return mean + stddev * Normal(); }

double RngStream::Exponential(double mean) { return -mean * std::log1p(-Uniform()); }

double RngStream::Pareto(double scale, double shape) {
  return scale / std::pow(1.0 - Uniform(), 1.0 / shape);
}

bool RngStream::Bernoulli(double p) { return Uniform() < p; }

}  // namespace uavsim::core
