#include "core/counter_normal.h"

#include <cmath>
#include <cstring>

#include "core/physical_constants.h"
#include "core/rng.h"

namespace uavsim::core {

namespace {

constexpr int kLayers = 256;
constexpr std::uint64_t kGolden = 0x9e3779b97f4a7c15ULL;
// Salt for the sequence of extra uniforms, so that it never retraces the
// main counter sequence.
constexpr std::uint64_t kExtraSalt = 0x2545f4914f6cdd1dULL;
constexpr double kTwoToMinus53 = 0x1.0p-53;

// core::Mix64, repeated here so the hot loop inlines it (rng.cpp keeps its
// definition out of line); counter_normal_test pins the two together through
// the stream's values.
inline std::uint64_t Mix(std::uint64_t x) {
  x += kGolden;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double Density(double x) { return std::exp(-0.5 * x * x); }

// Area of the unnormalised density exp(-x^2/2) beyond r.
double TailArea(double r) { return std::sqrt(0.5 * kPi) * std::erfc(r / std::sqrt(2.0)); }

}  // namespace

// Layer i (0..255) is the rectangle [0, x[i]) x [f[i], f[i+1]) under
// f(x) = exp(-x^2/2), x decreasing from x[1] = r to x[256] = 0; every layer
// has area V. Layer 0 is the base: [0, r) x [0, f(r)) plus the tail beyond
// r, drawn as a rectangle of width x[0] = V / f(r).
struct CounterNormal::Tables {
  double x[kLayers + 1];
  double f[kLayers + 1];
  double x_scaled[kLayers + 1];  // x[i] * 2^-53: takes 53 raw bits to [0, x[i])
  double r;

  Tables() {
    // r solves "256 layers of equal area exactly reach f = 1": bisect on
    // whether the stack of layers built from r tops out early (r too small).
    double lo = 3.0, hi = 4.0;
    for (int it = 0; it < 200 && lo < hi; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (mid == lo || mid == hi) break;
      (Build(mid) ? lo : hi) = mid;
    }
    r = hi;
    Build(r);
    for (int i = 0; i <= kLayers; ++i) x_scaled[i] = x[i] * kTwoToMinus53;
  }

  // Builds the stack from r; true if a layer reaches f = 1 before the last.
  bool Build(double r_try) {
    const double fr = Density(r_try);
    const double v = r_try * fr + TailArea(r_try);
    x[0] = v / fr;
    x[1] = r_try;
    f[0] = 0.0;
    f[1] = fr;
    for (int i = 1; i < kLayers; ++i) {
      const double f_next = v / x[i] + f[i];
      if (f_next >= 1.0) return i < kLayers - 1 || f_next > 1.0;
      x[i + 1] = std::sqrt(-2.0 * std::log(f_next));
      f[i + 1] = f_next;
    }
    x[kLayers] = 0.0;
    f[kLayers] = 1.0;
    return false;
  }
};

namespace {

const CounterNormal::Tables& SharedTables() {
  static const CounterNormal::Tables tables;
  return tables;
}

// Uniform in [0, 1) and in (0, 1] from the top 53 bits.
double Uniform53(std::uint64_t bits) { return static_cast<double>(bits >> 11) * kTwoToMinus53; }
double UniformOpen0(std::uint64_t bits) {
  return static_cast<double>((bits >> 11) + 1) * kTwoToMinus53;
}

// -x if bit 8 of `bits` is set: flips the sign bit without a branch (the
// sign is a coin toss, so a branch would be mispredicted half the time).
double WithSign(double x, std::uint64_t bits) {
  std::uint64_t u;
  std::memcpy(&u, &x, sizeof u);
  u ^= (bits & 0x100) << 55;
  std::memcpy(&x, &u, sizeof x);
  return x;
}

// The rare draws: a wedge, the tail or a retry. `bits` failed the fast test;
// the extra uniforms come from a SplitMix64 sequence seeded by `bits` itself.
[[gnu::noinline]] double Slow(const CounterNormal::Tables& t, std::uint64_t bits) {
  std::uint64_t state = bits ^ kExtraSalt;
  auto next = [&state] {
    state += kGolden;
    return Mix(state);
  };
  for (;;) {
    const unsigned layer = static_cast<unsigned>(bits & 0xff);
    const double x = Uniform53(bits) * t.x[layer];
    if (x < t.x[layer + 1]) return WithSign(x, bits);
    if (layer == 0) {
      // Marsaglia (1964): r + a with a ~ Exp(r) thinned by exp(-a^2/2).
      double a, b;
      do {
        a = -std::log(UniformOpen0(next())) / t.r;
        b = -std::log(UniformOpen0(next()));
      } while (b + b < a * a);
      return WithSign(t.r + a, bits);
    }
    const double y = t.f[layer] + (t.f[layer + 1] - t.f[layer]) * Uniform53(next());
    if (y < Density(x)) return WithSign(x, bits);
    bits = next();
  }
}

template <class Out>
void FillImpl(const CounterNormal::Tables& t, std::uint64_t counter, Out* out, std::size_t n) {
  // The same products as Slow's Uniform53(bits) * t.x[layer], bit for bit
  // (scaling by 2^-53 is exact), one multiply fewer.
  const double* xs = t.x_scaled;
  const double* edge = t.x;
  for (std::size_t j = 0; j < n; ++j, counter += kGolden) {
    const std::uint64_t bits = Mix(counter);
    const unsigned layer = static_cast<unsigned>(bits & 0xff);
    const double x = static_cast<double>(bits >> 11) * xs[layer];
    out[j] = static_cast<Out>(x < edge[layer + 1] ? WithSign(x, bits) : Slow(t, bits));
  }
}

}  // namespace

CounterNormal::CounterNormal(std::uint64_t key)
    : key_(key), mixed_key_(Mix64(key)), tables_(&SharedTables()) {}

double CounterNormal::At(std::uint64_t index) const {
  double z;
  FillImpl(*tables_, mixed_key_ + index * kGolden, &z, 1);
  return z;
}

void CounterNormal::Fill(std::uint64_t first_index, double* out, std::size_t n) const {
  FillImpl(*tables_, mixed_key_ + first_index * kGolden, out, n);
}

void CounterNormal::Fill(std::uint64_t first_index, float* out, std::size_t n) const {
  FillImpl(*tables_, mixed_key_ + first_index * kGolden, out, n);
}

}  // namespace uavsim::core
