#include "pipeline/node/ib_model_io.h"

#include <filesystem>
#include <map>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_io.h"
#include "core/zip_check.h"

namespace uavsim::pipeline {
namespace {

namespace fs = std::filesystem;

std::string ShapeText(const std::vector<std::int64_t>& shape) {
  std::string s = "[";
  for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

// Shapes of every parameter and buffer, by qualified name.
std::map<std::string, std::vector<std::int64_t>> TensorShapes(const torch::nn::Module& m) {
  std::map<std::string, std::vector<std::int64_t>> shapes;
  for (const auto& p : m.named_parameters()) shapes[p.key()] = p.value().sizes().vec();
  for (const auto& b : m.named_buffers()) shapes[b.key()] = b.value().sizes().vec();
  return shapes;
}

}  // namespace

template <class V>
void Visit(V& v, IbModelFile& c) {
  v("format", c.format);
  v.Check(c.format == IbModelFile::kFormat, "format",
          std::string("expected \"") + IbModelFile::kFormat + "\", got \"" + c.format + "\"");
  v("weights", c.weights);
  v.Check(!c.weights.empty() && fs::path(c.weights).filename() == fs::path(c.weights), "weights",
          "expected the weights' file name (no folder), got \"" + c.weights + "\"");
  v("note", c.note);
  v.Check(v.Has("config"), "config", "expected the model's config object");
  v.Object("config", c.config);
}
UAVSIM_INSTANTIATE_VISIT(IbModelFile);

void SaveIbCcModel(const IbCcModel& model, const std::string& json_path, const std::string& note) {
  const fs::path sidecar(json_path);
  fs::path weights = sidecar;
  weights.replace_extension(".pt");
  if (weights == sidecar) throw std::runtime_error(json_path + ": the sidecar must not end in .pt");

  try {
    core::WriteViaTemporary(weights.string(),
                            [&](const std::string& temp) { torch::save(model, temp); });
  } catch (const c10::Error& e) {
    throw std::runtime_error(weights.string() + ": cannot write: " + e.what_without_backtrace());
  }

  IbModelFile file;
  file.format = IbModelFile::kFormat;
  file.weights = weights.filename().string();
  file.note = note;
  file.config = model->config();
  core::WriteFileAtomic(json_path, core::ToJson(file).dump(2) + "\n");
}

IbModelFile ReadIbCcSidecar(const std::string& json_path) {
  IbModelFile file;
  core::FromJson(core::LoadJsonFile(json_path), json_path, "", file);
  return file;
}

IbCcModel LoadIbCcModel(const std::string& json_path) {
  const IbModelFile file = ReadIbCcSidecar(json_path);
  const fs::path weights = fs::path(json_path).parent_path() / file.weights;
  std::error_code ec;
  if (!fs::is_regular_file(weights, ec))
    throw core::ConfigError(json_path, "/weights", "file not found: " + weights.string());
  IbCcModel model(file.config);
  const std::string misfit = weights.string() + ": weights do not fit the " +
                             ModalityName(file.config.modality) + " model configured in " +
                             json_path + ": ";
  const std::map<std::string, std::vector<std::int64_t>> shapes = TensorShapes(*model);
  core::RequireWholeZip(weights.string());  // a truncated file says so (issue 43)
  try {
    torch::load(model, weights.string());
  } catch (const c10::Error& e) {
    throw std::runtime_error(misfit + e.what_without_backtrace());
  }
  // torch::load replaces each tensor whatever its shape; a file from another
  // latent size would load "successfully" and fail later, so compare here.
  for (const auto& [name, shape] : TensorShapes(*model))
    if (shapes.at(name) != shape)
      throw std::runtime_error(misfit + name + " has shape " + ShapeText(shape) + ", expected " +
                               ShapeText(shapes.at(name)));
  model->eval();
  return model;
}

}  // namespace uavsim::pipeline
