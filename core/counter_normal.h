// Counter-based standard normal numbers: the value at (key, index) is a pure
// function of the two, so a row of pixels may fill its noise in any order, in
// blocks of any size, from any thread, with no shared state (Salmon et al.,
// "Parallel random numbers: as easy as 1, 2, 3", SC 2011).
//
// Uniform bits: SplitMix64 read as a counter, bits(key, i) = Mix64(k + i * g)
// with k = Mix64(key) and g = 0x9e3779b97f4a7c15 (Steele, Lea and Flood 2014).
// Normals: a 256-layer Ziggurat (Marsaglia and Tsang 2000) with disjoint bits
// for the layer (8), the sign (1) and the abscissa (53), the exact wedge test
// and Marsaglia's exact tail beyond r = 3.6541528853610088. About 1.5% of
// draws need more uniforms (a wedge, the tail or a retry); they come from a
// SplitMix64 sequence seeded by that index's own bits, so every value stays a
// function of (key, index) alone. The tables are built once, in double, the
// first time a CounterNormal is constructed.
//
// Distribution: exactly N(0, 1) up to the 2^-53 grid of the abscissa, in
// double; the float outputs are those doubles rounded to nearest. Symmetric
// about 0 (the sign is its own bit); beyond r the tail is exact too, to the
// 2^-53 grid of its uniforms (|z| < 12.3).
//
// Determinism: At(i), Fill(first, out, n)[j] == At(first + j) for every
// block size and offset, on every thread count. The fast path (98.5% of
// draws) is integer arithmetic and one multiply by a table entry; the tables
// and the rare wedge and tail draws call std::exp, std::log and std::sqrt, so
// another libm may change the last bit of a double (a wedge or tail decision
// only if a uniform lands within an ulp of its boundary). The same platform
// and build always give the same numbers. Thread-safe: every method is const.
#pragma once

#include <cstddef>
#include <cstdint>

namespace uavsim::core {

class CounterNormal {
 public:
  // The stream of `key`, any 64-bit value: nearby keys (k, k + 1) give
  // unrelated streams, since the key is mixed first.
  explicit CounterNormal(std::uint64_t key);

  // The standard normal at `index`.
  double At(std::uint64_t index) const;

  // out[j] = At(first_index + j) for j in [0, n); the index wraps modulo 2^64.
  void Fill(std::uint64_t first_index, double* out, std::size_t n) const;
  // out[j] = static_cast<float>(At(first_index + j)).
  void Fill(std::uint64_t first_index, float* out, std::size_t n) const;

  std::uint64_t key() const { return key_; }

  struct Tables;  // the Ziggurat's layer edges and densities (counter_normal.cpp)

 private:
  std::uint64_t key_;
  std::uint64_t mixed_key_;
  const Tables* tables_;
};

}  // namespace uavsim::core
