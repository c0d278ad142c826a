// libFuzzer target: the readers of the files a trained model and a training
// read besides JSON scenarios. The input's first byte says which file the
// rest is, written to a temporary folder and read as uavsim reads it:
//   'M'  a model's model.json: ReadModelManifest, then ReadEdgeHeads (the
//        manifest's heads' sidecars are absent, so a manifest that parses
//        is refused there, naming it)
//   'C'  a model folder's checksums.sha256: VerifyModelChecksums (no other
//        file in the folder: a well-formed entry is refused as missing)
//   'E'  an episode file (`uavsim train --data`): ReadEpisodes
// other bytes pick one of the three by their value. Every refusal must be a
// core::ConfigError naming the file (fuzz_support.h); anything else, a
// crash or a sanitizer report is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_support.h"
#include "pipeline/model_bundle.h"
#include "pipeline/model_checksums.h"
#include "pipeline/training/dataset_io.h"

namespace {

namespace fs = std::filesystem;

// A folder of this process's own, emptied for each input.
const fs::path& Scratch() {
  static const fs::path dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    fs::path d = fs::path(tmp && *tmp ? tmp : "/tmp") /
                 ("uavsim-model-files-fuzz-" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

std::string WriteInput(const std::string& name, const std::string& bytes) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(Scratch(), ec)) fs::remove_all(e.path(), ec);
  const fs::path p = Scratch() / name;
  std::ofstream(p, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return p.string();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace uavsim;
  if (size == 0) return 0;
  const char kind = static_cast<char>(data[0]);
  const char which = kind == 'M' || kind == 'C' || kind == 'E' ? kind : "MCE"[data[0] % 3];
  fuzz::RunLoader(data + 1, size - 1, [which](const std::string& bytes) {
    if (which == 'M') {
      const std::string path = WriteInput("model.json", bytes);
      const pipeline::ModelManifest m = pipeline::ReadModelManifest(path);
      (void)pipeline::ReadEdgeHeads(m, path);
    } else if (which == 'C') {
      WriteInput(pipeline::kModelChecksumsFile, bytes);
      pipeline::VerifyModelChecksums(Scratch().string());
    } else {
      (void)pipeline::ReadEpisodes(WriteInput("episodes.eps", bytes));
    }
  });
  return 0;
}
