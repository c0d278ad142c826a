// uavsim.PythonMethod in the loop: a hosted localization method
// (sim/hosted_method.h) that calls a Python function at each window's
// deadline with what a TorchScript method is given
// (pipeline/edge/latent_history.h) as NumPy arrays:
//   fn(latents [L, 3, F, z], offsets_s [L, 3, F], mask [L, 3, F][, t_end_s]) -> 3 numbers or None
// Called on the run's thread with the GIL taken for the call only. The
// function's exception propagates (py::error_already_set) and ends the run;
// so does a return value that is not None or 3 finite numbers (Position).
#include <pybind11/numpy.h>

#include <cmath>
#include <optional>
#include <string>

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

// What a function returned, for an error: its type and the start of its
// repr, on one line (an array's repr spans several).
std::string Shown(const py::handle& out) {
  std::string shown = Py_TYPE(out.ptr())->tp_name;
  try {
    py::str r = py::str(" ").attr("join")(py::repr(out).attr("split")());
    if (py::len(r) > 60) r = py::str("{}...").format(r[py::slice(0, 57, 1)]);
    shown += " " + r.cast<std::string>();
  } catch (const std::exception&) {  // a repr that raises, or text that is not UTF-8
  }
  return shown;
}

// `out` as a position, None as no estimate. Anything else raises a TypeError
// (not numbers, not 3 of them) or a ValueError (not finite) naming the
// method, the window and what came back: NumPy's own errors ("could not
// convert string to float: 'abc'") name neither. NumPy's error on a ragged
// list is the cause of ours.
std::optional<Eigen::Vector3d> Position(const py::object& out, const std::string& method,
                                        std::int64_t k) {
  if (out.is_none()) return std::nullopt;
  const auto message = [&](const std::string& why) {
    return "PythonMethod \"" + method + "\" returned " + Shown(out) + " at window " +
           std::to_string(k) + ": " + why +
           "; expected 3 numbers (x, y, z: world ENU metres) or None";
  };
  // Text is refused whole: NumPy reads "123" and bytearray(b"abc") as numbers.
  const bool text = py::isinstance<py::str>(out) || py::isinstance<py::bytes>(out) ||
                    PyByteArray_Check(out.ptr());
  py::array a;
  if (!text) {
    try {
      a = py::module_::import("numpy").attr("asarray")(out);
    } catch (py::error_already_set& e) {
      if (!e.matches(PyExc_Exception)) throw;  // KeyboardInterrupt, SystemExit
      py::raise_from(e, PyExc_TypeError, message("not numbers").c_str());
      throw py::error_already_set();
    }
  }
  // Integers and floats: not bool, complex, text, objects (dicts, None in a list).
  if (text || std::string("iuf").find(a.dtype().kind()) == std::string::npos)
    throw py::type_error(message("not numbers"));
  if (a.size() != 3) throw py::type_error(message(std::to_string(a.size()) + " values"));
  const auto v = a.attr("astype")("float64").attr("reshape")(-1).cast<py::array_t<double>>();
  if (!std::isfinite(v.at(0)) || !std::isfinite(v.at(1)) || !std::isfinite(v.at(2)))
    throw py::value_error(message("not finite"));
  return Eigen::Vector3d(v.at(0), v.at(1), v.at(2));
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
    return Position(out, name(), w.k);
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
