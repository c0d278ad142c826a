#include "pipeline/edge/scripted_edge.h"

#include <torch/script.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <utility>

#include "core/error.h"
#include "core/zip_check.h"
#include "pipeline/edge/latent_history.h"

namespace uavsim::pipeline {
namespace {

constexpr int kMaxHistoryWindows = 10000;

const char* const kSignature =
    "forward(latents: float32 [L, 3, F, z], offsets_s: float32 [L, 3, F], mask: float32 "
    "[L, 3, F]) -> 3 numbers (x, y, z: world ENU metres)";

// The first line of a LibTorch message (they run to a traceback).
std::string FirstLine(const std::string& s) {
  const auto end = s.find('\n');
  return end == std::string::npos ? s : s.substr(0, end);
}

// One line saying what went wrong: the first line of LibTorch's message,
// or, when the model raised (the message opens with the interpreter's
// preamble and a TorchScript traceback), its last line: the exception.
std::string Gist(const std::string& s) {
  const std::string first = FirstLine(s);
  if (first.rfind("The following operation failed in the TorchScript interpreter", 0) != 0)
    return first;
  std::size_t end = s.find_last_not_of(" \n");
  if (end == std::string::npos) return first;
  const std::size_t begin = s.rfind('\n', end);
  return s.substr(begin == std::string::npos ? 0 : begin + 1, end + 1 - (begin + 1));
}

}  // namespace

struct ScriptedEdge::Impl {
  torch::jit::script::Module module;
  std::string path;
  int latent_dim = 16;
  double window_s = 0.2;
  std::optional<LatentHistory> history;  // made once history_windows is read

  // The model's output for the windows held (padded to history_windows).
  torch::Tensor Forward() {
    PackedWindows p = history->Pack();
    const std::int64_t L = p.windows, F = p.frames;
    const auto tensor = [](std::vector<float>& data, c10::IntArrayRef shape) {
      return torch::from_blob(data.data(), shape, torch::kFloat32).clone();
    };
    torch::NoGradGuard no_grad;
    const torch::jit::IValue out = module.forward(
        {tensor(p.latents, {L, kModalityCount, F, p.latent_dim}),
         tensor(p.offsets_s, {L, kModalityCount, F}), tensor(p.mask, {L, kModalityCount, F})});
    if (!out.isTensor()) throw std::runtime_error("returned no tensor");
    return out.toTensor();
  }
};

ScriptedEdge::ScriptedEdge(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ScriptedEdge::~ScriptedEdge() = default;

std::unique_ptr<ScriptedEdge> ScriptedEdge::Load(const std::string& path, int latent_dim,
                                                 double window_s) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::invalid_argument("no TorchScript file at " + path);
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->latent_dim = latent_dim;
  impl->window_s = window_s;
  try {
    core::RequireWholeZip(path);  // a truncated file says so (issue 43)
  } catch (const core::ConfigError& e) {
    throw std::invalid_argument(e.what());
  }
  try {
    impl->module = torch::jit::load(path, torch::kCPU);
  } catch (const c10::Error& e) {
    throw std::invalid_argument(path + " is not a TorchScript file torch.jit.save wrote (" +
                                FirstLine(e.what_without_backtrace()) + ")");
  }
  impl->module.eval();
  const auto forward = impl->module.find_method("forward");
  if (!forward)
    throw std::invalid_argument(path + " has no forward method: expected " + kSignature);
  // The schema's first argument is the module itself.
  const auto& args = forward->function().getSchema().arguments();
  if (args.size() != 4)
    throw std::invalid_argument(path + ": forward takes " +
                                std::to_string(args.size() > 0 ? args.size() - 1 : 0) +
                                " arguments: expected " + kSignature);
  int history = 1;
  if (impl->module.hasattr("history_windows")) {
    const torch::jit::IValue h = impl->module.attr("history_windows");
    if (!h.isInt() || h.toInt() < 1 || h.toInt() > kMaxHistoryWindows)
      throw std::invalid_argument(path + ": history_windows must be an integer from 1 to " +
                                  std::to_string(kMaxHistoryWindows));
    history = static_cast<int>(h.toInt());
  }
  impl->history.emplace(history, latent_dim, window_s);
  torch::Tensor out;
  try {
    out = impl->Forward();
  } catch (const std::exception& e) {
    std::string what = e.what();
    if (const auto* c10 = dynamic_cast<const c10::Error*>(&e)) what = c10->what_without_backtrace();
    throw std::invalid_argument(path + ": calling it on padding failed (" + FirstLine(what) +
                                "): expected " + kSignature);
  }
  if (out.numel() != 3 || !out.is_floating_point())
    throw std::invalid_argument(path + ": forward returned a " + std::string(out.dtype().name()) +
                                " tensor of " + std::to_string(out.numel()) + " values: expected " +
                                kSignature);
  return std::unique_ptr<ScriptedEdge>(new ScriptedEdge(std::move(impl)));
}

std::optional<Eigen::Vector3d> ScriptedEdge::OnWindow(const WindowInputs& window) {
  Impl& s = *impl_;
  try {
    s.history->Push(window);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("ScriptedEdge::OnWindow: ") + e.what());
  }
  if (!s.history->has_seen_data()) return std::nullopt;
  torch::Tensor out;
  try {
    out = s.Forward().to(torch::kDouble).reshape({3}).contiguous();
  } catch (const std::exception& e) {
    const auto* c10 = dynamic_cast<const c10::Error*>(&e);
    const std::string what = c10 ? c10->what_without_backtrace() : e.what();
    throw ScriptedEdgeFailure(
        s.path + ": forward failed at window " + std::to_string(window.window) + ": " + Gist(what),
        what);
  }
  // A non-finite value is passed on: the run counts it as no estimate.
  return Eigen::Vector3d(out[0].item<double>(), out[1].item<double>(), out[2].item<double>());
}

ScriptedEdgeFailure::ScriptedEdgeFailure(const std::string& line, std::string traceback)
    : std::runtime_error(line), traceback_(std::move(traceback)) {}

int ScriptedEdge::history_windows() const { return impl_->history->history_windows(); }
int ScriptedEdge::latent_dim() const { return impl_->latent_dim; }

}  // namespace uavsim::pipeline
