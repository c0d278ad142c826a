// A user's TorchScript edge model (pipeline/edge/scripted_edge.h): the
// tensors it is given, worked by hand, and the files it refuses. The modules
// are written here with LibTorch's own TorchScript compiler (Module::define),
// independently of the code under test.
#include <torch/script.h>
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "pipeline/edge/scripted_edge.h"
#include "test_support.h"

namespace {

using uavsim::pipeline::LatentFrame;
using uavsim::pipeline::ScriptedEdge;
using uavsim::pipeline::WindowInputs;

// Saves a module whose forward is `body` (TorchScript source of the method)
// and returns its path.
std::string SaveModule(const std::string& dir, const std::string& name, const std::string& body,
                       int history = 0) {
  torch::jit::Module m("M");
  if (history > 0) m.register_attribute("history_windows", c10::IntType::get(), history);
  m.define(body);
  const std::string path = dir + "/" + name + ".pt";
  m.save(path);
  return path;
}

LatentFrame Frame(double t_s, std::vector<float> latent) {
  LatentFrame f;
  f.t_s = t_s;
  f.latent = std::move(latent);
  return f;
}

const char* const kSummary = R"(
def forward(self, latents, offsets_s, mask):
    return torch.stack([mask.sum(), (offsets_s * mask).sum(),
                        latents.sum() + 100.0 * float(latents.size(0))])
)";

}  // namespace

TEST_CASE(
    "ScriptedEdge: a model gets each window's latents, capture offsets and mask, "
    "oldest window first, frames in capture order",
    "[pipeline][scripted]") {
  const std::string dir = uavsim::testing::TempDir("scripted-edge");
  // Window L - 1's first camera frame's first value, its offset, and the
  // padded shape: what the module sees, read back.
  const std::string first = SaveModule(dir, "first", R"(
def forward(self, latents, offsets_s, mask):
    L = latents.size(0)
    return torch.stack([latents[L - 1, 0, 0, 0], offsets_s[L - 1, 0, 0],
                        float(latents.size(2)) + 0.0 * mask.sum()])
)",
                                       3);
  auto edge = ScriptedEdge::Load(first, 2, 0.2);
  CHECK(edge->history_windows() == 3);
  WindowInputs w;
  w.window = 4;                                                          // covers [0.6, 0.8) s
  w.frames[0] = {Frame(0.75, {7.0f, 0.0f}), Frame(0.65, {5.0f, 0.0f})};  // out of order
  w.frames[1] = {Frame(0.61, {1.0f, 1.0f}), Frame(0.62, {1.0f, 1.0f}), Frame(0.63, {1.0f, 1.0f})};
  const auto p = edge->OnWindow(w);
  REQUIRE(p);
  CHECK((*p)(0) == Approx(5.0));                // the earlier camera frame comes first
  CHECK((*p)(1) == Approx(0.05).margin(1e-6));  // 0.65 - (4 - 1) * 0.2
  CHECK((*p)(2) == Approx(3.0));                // F: LiDAR's three frames

  // Sums over what the module is given, two windows of history.
  const std::string summary = SaveModule(dir, "summary", kSummary, 2);
  auto s = ScriptedEdge::Load(summary, 2, 0.2);
  WindowInputs a;
  a.window = 1;
  CHECK_FALSE(s->OnWindow(a));  // nothing seen yet: no estimate
  WindowInputs b;
  b.window = 2;  // [0.2, 0.4)
  b.frames[2] = {Frame(0.3, {1.0f, 2.0f})};
  const auto pb = s->OnWindow(b);
  REQUIRE(pb);
  CHECK((*pb)(0) == Approx(1.0));               // one frame
  CHECK((*pb)(1) == Approx(0.1).margin(1e-6));  // its offset
  CHECK((*pb)(2) == Approx(203.0));             // its latent's sum + 100 L, L = 2
  // Window 3 skipped: window 4 holds its own frames and window 3 is empty,
  // so window 2 has left the two-window history.
  WindowInputs d;
  d.window = 4;
  d.frames[0] = {Frame(0.7, {0.5f, 0.5f})};
  const auto pd = s->OnWindow(d);
  REQUIRE(pd);
  CHECK((*pd)(0) == Approx(1.0));
  CHECK((*pd)(1) == Approx(0.1).margin(1e-6));
  CHECK((*pd)(2) == Approx(201.0));
  // Windows must come in order, latents of the model's size.
  CHECK_THROWS_AS(s->OnWindow(d), std::invalid_argument);
  WindowInputs e;
  e.window = 5;
  e.frames[1] = {Frame(0.9, {1.0f, 2.0f, 3.0f})};
  CHECK_THROWS_AS(s->OnWindow(e), std::invalid_argument);
}

TEST_CASE(
    "ScriptedEdge: without history_windows a model sees the current window only; a "
    "non-finite output is passed on for the run to reject",
    "[pipeline][scripted]") {
  const std::string dir = uavsim::testing::TempDir("scripted-edge");
  auto s = ScriptedEdge::Load(SaveModule(dir, "one", kSummary), 4, 0.2);
  CHECK(s->history_windows() == 1);
  WindowInputs w;
  w.window = 1;
  w.frames[0] = {Frame(0.1, {1, 1, 1, 1})};
  const auto p1 = s->OnWindow(w);
  REQUIRE(p1);
  CHECK((*p1)(2) == Approx(104.0));  // L = 1
  WindowInputs x;
  x.window = 2;
  const auto p2 = s->OnWindow(x);  // an empty window after data: still answers
  REQUIRE(p2);
  CHECK((*p2)(0) == Approx(0.0));
  CHECK((*p2)(2) == Approx(100.0));
  auto nan = ScriptedEdge::Load(SaveModule(dir, "nan", R"(
def forward(self, latents, offsets_s, mask):
    return torch.full([1, 3], float('nan'))
)"),
                                4, 0.2);
  // The run's scorer counts it in rejected_estimates (issue 43) rather than
  // dropping it unseen.
  const auto p3 = nan->OnWindow(w);
  REQUIRE(p3);
  CHECK_FALSE(p3->allFinite());
}

TEST_CASE(
    "ScriptedEdge: a model that fails at run time says which file, at which window, on one "
    "line",
    "[pipeline][scripted]") {
  // Issue 43: "shape '[3]' is invalid for input of size 10" named nothing;
  // a raise printed a multi-line TorchScript traceback.
  const std::string dir = uavsim::testing::TempDir("scripted-edge-fails");
  const auto failure_of = [](ScriptedEdge& s, const WindowInputs& w) {
    try {
      s.OnWindow(w);
    } catch (const uavsim::pipeline::ScriptedEdgeFailure& e) {
      return std::make_pair(std::string(e.what()), e.traceback());
    }
    return std::make_pair(std::string("no failure"), std::string());
  };
  WindowInputs w;
  w.window = 7;
  w.frames[0] = {Frame(1.3, {1, 1, 1, 1})};
  // Three numbers on padding (Load's check), ten once a frame is there.
  const std::string wide = SaveModule(dir, "wide", R"(
def forward(self, latents, offsets_s, mask):
    return torch.zeros([3 + 7 * int(mask.sum() > 0.0)])
)");
  auto s = ScriptedEdge::Load(wide, 4, 0.2);
  const auto [line, traceback] = failure_of(*s, w);
  CHECK(line == wide + ": forward failed at window 7: shape '[3]' is invalid for input of size 10");
  const std::string raises = SaveModule(dir, "raises", R"(
def forward(self, latents, offsets_s, mask):
    assert bool(mask.sum() == 0.0), "no luck with this window"
    return torch.zeros([3])
)");
  auto r = ScriptedEdge::Load(raises, 4, 0.2);
  const auto [raised, raised_traceback] = failure_of(*r, w);
  CHECK_THAT(raised, Catch::StartsWith(raises + ": forward failed at window 7: "));
  CHECK_THAT(raised, Catch::EndsWith("no luck with this window"));
  CHECK(raised.find('\n') == std::string::npos);
  CHECK_THAT(raised_traceback, Catch::Contains("Traceback"));
}

TEST_CASE("ScriptedEdge: files that are not such a model are refused with what was expected",
          "[pipeline][scripted]") {
  const std::string dir = uavsim::testing::TempDir("scripted-edge");
  auto refused = [&](const std::string& path, const std::string& says) {
    try {
      ScriptedEdge::Load(path, 16, 0.2);
      FAIL("accepted " << path);
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      INFO(what);
      CHECK(what.find(says) != std::string::npos);
      CHECK(what.find('\n') == std::string::npos);
    }
  };
  refused(dir + "/missing.pt", "no TorchScript file");
  { std::ofstream(dir + "/junk.pt") << "not a zip"; }
  refused(dir + "/junk.pt", "is not a TorchScript file");
  refused(SaveModule(dir, "one_arg", R"(
def forward(self, x):
    return x
)"),
          "forward takes 1 arguments: expected forward(latents");
  refused(SaveModule(dir, "four", R"(
def forward(self, latents, offsets_s, mask):
    return torch.zeros([4])
)"),
          "tensor of 4 values: expected forward(latents");
  refused(SaveModule(dir, "fails", R"(
def forward(self, latents, offsets_s, mask):
    return latents.view([5, 7])
)"),
          "calling it on padding failed");
  torch::jit::Module m("M");
  m.register_attribute("history_windows", c10::IntType::get(), 0);
  m.define(kSummary);
  m.save(dir + "/h0.pt");
  refused(dir + "/h0.pt", "history_windows must be an integer from 1");
}
