// The packing a TorchScript and a Python method are given
// (pipeline/edge/latent_history.h), checked cell by cell on hand-built windows.
#include "pipeline/edge/latent_history.h"

#include <catch2/catch.hpp>

using uavsim::pipeline::LatentFrame;
using uavsim::pipeline::LatentHistory;
using uavsim::pipeline::WindowInputs;

namespace {

WindowInputs Window(std::int64_t k) {
  WindowInputs w;
  w.window = k;
  return w;
}

LatentFrame Frame(double t_s, float value) { return {t_s, {value, -value}, {}}; }

}  // namespace

TEST_CASE("LatentHistory: windows, modalities and frames land where the contract says",
          "[pipeline]") {
  LatentHistory h(3, 2, 0.2);
  WindowInputs w1 = Window(1);
  h.Push(w1);  // empty: nothing seen yet
  CHECK_FALSE(h.has_seen_data());
  WindowInputs w3 = Window(3);                            // window 2 skipped: padding
  w3.frames[1] = {Frame(0.55, 7.0f), Frame(0.45, 5.0f)};  // LiDAR, out of capture order
  w3.frames[2] = {Frame(0.41, 9.0f)};
  h.Push(w3);
  REQUIRE(h.has_seen_data());
  const auto p = h.Pack();
  REQUIRE(p.windows == 3);
  REQUIRE(p.frames == 2);
  REQUIRE(p.latent_dim == 2);
  const auto cell = [&](int l, int m, int f) { return (l * 3 + m) * 2 + f; };
  // The newest window is l = 2; its LiDAR frames sorted by capture time.
  CHECK(p.latents[cell(2, 1, 0) * 2] == 5.0f);
  CHECK(p.latents[cell(2, 1, 0) * 2 + 1] == -5.0f);
  CHECK(p.latents[cell(2, 1, 1) * 2] == 7.0f);
  CHECK(p.offsets_s[cell(2, 1, 0)] == Approx(0.45 - 0.4));
  CHECK(p.offsets_s[cell(2, 2, 0)] == Approx(0.41 - 0.4));
  CHECK(p.mask[cell(2, 1, 1)] == 1.0f);
  CHECK(p.mask[cell(2, 2, 1)] == 0.0f);  // radar's one frame, then padding
  CHECK(p.mask[cell(2, 0, 0)] == 0.0f);  // no camera
  // Windows 1 (l = 0) and 2 (l = 1) are empty.
  float before = 0.0f;
  for (int l = 0; l < 2; ++l)
    for (int m = 0; m < 3; ++m)
      for (int f = 0; f < 2; ++f) before += p.mask[cell(l, m, f)];
  CHECK(before == 0.0f);
}

TEST_CASE("LatentHistory: the oldest window leaves; bad input is refused", "[pipeline]") {
  LatentHistory h(2, 2, 0.2);
  WindowInputs a = Window(1), b = Window(2), c = Window(3);
  a.frames[0] = {Frame(0.1, 1.0f)};
  b.frames[0] = {Frame(0.3, 2.0f)};
  c.frames[0] = {Frame(0.5, 3.0f)};
  h.Push(a);
  h.Push(b);
  h.Push(c);
  const auto p = h.Pack();
  REQUIRE(p.frames == 1);
  CHECK(p.latents[0] == 2.0f);      // l = 0: window 2
  CHECK(p.latents[3 * 2] == 3.0f);  // l = 1: window 3
  CHECK_THROWS_AS(h.Push(Window(3)), std::invalid_argument);
  WindowInputs wrong = Window(4);
  wrong.frames[0] = {{0.7, {1.0f, 2.0f, 3.0f}, {}}};
  CHECK_THROWS_AS(h.Push(wrong), std::invalid_argument);
  CHECK_THROWS_AS(LatentHistory(0, 2, 0.2), std::invalid_argument);
}
