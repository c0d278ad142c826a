// uavsim.PythonMethod in the loop: a hosted localization method
// (sim/hosted_method.h) that calls a Python function at each window's
// deadline with what a TorchScript method is given
// (pipeline/edge/latent_history.h) as NumPy arrays:
//   fn(latents [L, 3, F, z], offsets_s [L, 3, F], mask [L, 3, F][, t_end_s]) -> 3 numbers or None
// Called on the run's thread with the GIL taken for the call only. The
// function's exception propagates (py::error_already_set) and ends the run.
#include <pybind11/numpy.h>

#include <optional>

#include "apps/python/bindings.h"
#include "pipeline/edge/latent_history.h"
#include "pipeline/localization_method.h"

namespace uavsim::python {
namespace {

py::array_t<float> Array(const std::vector<float>& data, std::vector<py::ssize_t> shape) {
  py::array_t<float> a(shape);
  std::copy(data.begin(), data.end(), a.mutable_data());
  return a;
}

class PythonLocalization final : public pipeline::LocalizationMethod {
 public:
  // `fn`: borrowed; the caller keeps it alive while the run lasts.
  PythonLocalization(const pipeline::HostedMethod& entry, PyObject* fn, bool window_time,
                     int latent_dim, double window_s)
      : LocalizationMethod(entry.name, {false, true, false}, /*steers_beam=*/true),
        fn_(fn),
        window_time_(window_time),
        history_(entry.history_windows, latent_dim, window_s) {}

 private:
  std::optional<Eigen::Vector3d> DoEstimate(const pipeline::WindowArrivals& w) override {
    history_.Push(w.latents);
    if (!history_.has_seen_data() || !fn_) return std::nullopt;
    const pipeline::PackedWindows p = history_.Pack();
    const py::ssize_t L = p.windows, F = p.frames, z = p.latent_dim, M = 3;
    py::gil_scoped_acquire gil;
    const auto fn = py::reinterpret_borrow<py::object>(fn_);
    py::array latents = Array(p.latents, {L, M, F, z}), offsets = Array(p.offsets_s, {L, M, F}),
              mask = Array(p.mask, {L, M, F});
    const py::object out =
        window_time_ ? fn(latents, offsets, mask, w.t_end_s) : fn(latents, offsets, mask);
    if (out.is_none()) return std::nullopt;
    const auto xyz =
        py::module_::import("numpy").attr("asarray")(out, "float64").attr("reshape")(-1);
    const auto values = xyz.cast<py::array_t<double>>();
    if (values.size() != 3)
      throw py::type_error("PythonMethod \"" + name() + "\" returned " +
                           std::to_string(values.size()) + " values at window " +
                           std::to_string(w.k) +
                           ": expected 3 numbers (x, y, z: world ENU metres) or None");
    return Eigen::Vector3d(values.at(0), values.at(1), values.at(2));
  }

  PyObject* fn_;
  bool window_time_;
  pipeline::LatentHistory history_;
};

}  // namespace

sim::HostedMethods HostedFrom(const py::dict& methods) {
  sim::HostedMethods hosted;
  for (const auto& [key, value] : methods) {
    PyObject* fn = nullptr;  // None: a check that runs nothing
    bool window_time = false;
    if (!value.is_none()) {
      const auto t = value.cast<py::tuple>();
      fn = t[0].ptr();
      window_time = t[1].cast<bool>();
    }
    hosted[key.cast<std::string>()] = [fn, window_time](const pipeline::HostedMethod& entry,
                                                        int latent_dim, double window_s) {
      return std::make_unique<PythonLocalization>(entry, fn, window_time, latent_dim, window_s);
    };
  }
  return hosted;
}

}  // namespace uavsim::python
