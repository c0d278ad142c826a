// Saving and loading one modality's trained IB-CC model: the weights (a
// LibTorch archive of the module's parameters and buffers) and a JSON sidecar
// with everything needed to rebuild the module before the weights are read:
//
//   camera.json  {"format": "uavsim-ibcc/1", "weights": "camera.pt",
//                 "note": "...", "config": { IbCcConfig }}
//   camera.pt    torch::save of the IbCcModel
//
// A model is addressed by its sidecar; "weights" is a file name relative to
// the sidecar's folder. Both files are written atomically (temp file, then
// rename).
#pragma once

#include <string>

#include "pipeline/node/ib_cc_config.h"
#include "pipeline/node/ib_encoder.h"

namespace uavsim::pipeline {

struct IbModelFile {
  static constexpr const char* kFormat = "uavsim-ibcc/1";
  std::string format;   // must be kFormat
  std::string weights;  // file name, relative to the sidecar's folder
  std::string note;     // provenance, free text (e.g. the train command and seed)
  IbCcConfig config;
};

template <class V>
void Visit(V& v, IbModelFile& c);

// Writes `json_path` and the weights beside it (same stem, extension .pt).
// Throws std::runtime_error naming the path if a file cannot be written.
void SaveIbCcModel(const IbCcModel& model, const std::string& json_path,
                   const std::string& note = "");

// Reads and checks a sidecar. Throws core::ConfigError naming the file and the
// JSON pointer for a missing file, bad JSON, an unknown key or a bad value.
IbModelFile ReadIbCcSidecar(const std::string& json_path);

// Rebuilds the model from its sidecar and reads its weights; the result is in
// eval() mode. Throws core::ConfigError for a bad sidecar or a missing weights
// file, std::runtime_error naming the weights file if they do not fit the
// configured architecture.
IbCcModel LoadIbCcModel(const std::string& json_path);

}  // namespace uavsim::pipeline
