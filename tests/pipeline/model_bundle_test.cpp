// The model folder (pipeline/model_bundle.h): the manifest's path, strict
// reading of the manifest, and UavLocModelFiles::Load refusing a folder with
// a missing or mismatched part, naming the file and JSON pointer.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "core/error.h"
#include "core/sha256.h"
#include "pipeline/edge/uavloc_model.h"
#include "pipeline/model_bundle.h"
#include "pipeline/model_checksums.h"
#include "pipeline/node/ib_encoder.h"
#include "pipeline/node/ib_model_io.h"
#include "pipeline/torch_runtime.h"
#include "test_support.h"

namespace uavsim::pipeline {
namespace {

namespace fs = std::filesystem;

// A complete model folder with untrained parts: encoders of latent size
// `z_encoders`, the paper's edge head of `z_edge` (and with `anchored` the
// anchored one too, uavloc_anchored.pt), a manifest saying `z_manifest`.
std::string ModelFolder(const std::string& tag, int z_encoders, int z_edge, int z_manifest,
                        bool anchored = false) {
  const std::string dir = testing::TempDir(tag);
  for (Modality m : {Modality::kCamera, Modality::kLidar, Modality::kRadar}) {
    IbCcConfig c;
    c.modality = m;
    c.latent_dim = z_encoders;
    IbCcModel model(c);
    model->eval();
    SaveIbCcModel(model, dir + "/" + ModalityName(m) + ".json", "model_bundle_test");
  }
  UavLocModelConfig edge;
  edge.latent_dim = z_edge;
  edge.d_model = 16;
  edge.layers = 1;
  SaveUavLocModel(UavLocModel(edge), dir + "/uavloc.pt");
  ModelManifest manifest;
  if (anchored) {
    edge.anchored = true;
    SaveUavLocModel(UavLocModel(edge), dir + "/uavloc_anchored.pt");
    manifest.anchored_edge = "uavloc_anchored.pt";
  }
  manifest.note = "model_bundle_test";
  manifest.latent_dim = z_manifest;
  WriteModelManifest(manifest, dir + "/model.json");
  return dir;
}

}  // namespace

TEST_CASE("ModelBundle: a folder names its model.json, a file itself", "[pipeline]") {
  const std::string dir = testing::TempDir("bundle-path");
  CHECK(ModelManifestPath(dir) == (fs::path(dir) / "model.json").string());
  const std::string file = dir + "/other.json";
  testing::WriteFile(file, "{}");
  CHECK(ModelManifestPath(file) == file);
  CHECK(ModelManifestPath(dir + "/missing.json") == dir + "/missing.json");
}

TEST_CASE("ModelBundle: the manifest round trips and is read strictly", "[pipeline]") {
  const std::string dir = testing::TempDir("bundle-manifest");
  ModelManifest m;
  m.note = "seed 3";
  m.scenario = "default";
  m.layout_hash = "feedbeef";
  m.latent_dim = 12;
  m.window_s = 0.25;
  m.camera = "cam.json";
  m.edge = "edge.pt";
  const std::string path = dir + "/model.json";
  WriteModelManifest(m, path);
  const ModelManifest r = ReadModelManifest(path);
  CHECK(r.format == ModelManifest::kFormat);
  CHECK(r.note == "seed 3");
  CHECK(r.scenario == "default");
  CHECK(r.layout_hash == "feedbeef");
  CHECK(r.latent_dim == 12);
  CHECK(r.window_s == 0.25);
  CHECK(r.camera == "cam.json");
  CHECK(r.lidar == "lidar.json");
  CHECK(r.radar == "radar.json");
  CHECK(r.edge == "edge.pt");
  CHECK(r.anchored_edge.empty());  // absent: no anchored head

  // Either edge head may be absent, or both (stage-1 encoders only).
  m.edge = "";
  m.anchored_edge = "anchored.pt";
  WriteModelManifest(m, path);
  CHECK(ReadModelManifest(path).edge.empty());
  CHECK(ReadModelManifest(path).anchored_edge == "anchored.pt");
  m.anchored_edge = "";
  WriteModelManifest(m, path);
  CHECK(ReadModelManifest(path).edge.empty());
  CHECK(ReadModelManifest(path).anchored_edge.empty());

  const std::string bad = dir + "/bad.json";
  testing::WriteFile(bad, "{\"format\": \"uavsim-model/1\", \"latent_dimm\": 8}\n");
  std::string what = testing::ConfigErrorOf([&] { ReadModelManifest(bad); });
  CHECK_THAT(what, Catch::Contains(bad));
  CHECK_THAT(what, Catch::Contains("/latent_dimm"));
  CHECK_THAT(what, Catch::Contains("unknown key"));

  testing::WriteFile(bad, "{\"format\": \"uavsim-model/1\", \"lidar\": \"../lidar.json\"}\n");
  what = testing::ConfigErrorOf([&] { ReadModelManifest(bad); });
  CHECK_THAT(what, Catch::Contains(bad));
  CHECK_THAT(what, Catch::Contains("/lidar"));

  testing::WriteFile(bad, "{\"format\": \"uavsim-model/2\"}\n");
  what = testing::ConfigErrorOf([&] { ReadModelManifest(bad); });
  CHECK_THAT(what, Catch::Contains("/format"));

  testing::WriteFile(bad, "{\"latent_dim\": 1}\n");
  CHECK_THAT(testing::ConfigErrorOf([&] { ReadModelManifest(bad); }),
             Catch::Contains("/latent_dim"));

  CHECK_THAT(testing::ConfigErrorOf([&] { ReadModelManifest(dir + "/missing.json"); }),
             Catch::Contains(dir + "/missing.json"));
}

TEST_CASE("ModelBundle: Load reads a complete folder by folder or manifest", "[pipeline]") {
  InitTorch(1, 51);
  const std::string dir = ModelFolder("bundle-load", 8, 8, 8);
  for (const std::string& path : {dir, dir + "/model.json"}) {
    INFO(path);
    const auto files = UavLocModelFiles::Load(path);
    CHECK(files->manifest().latent_dim == 8);
    CHECK(files->manifest().note == "model_bundle_test");
    CHECK(files->manifest_path() == (fs::path(dir) / "model.json").string());
    for (Modality m : {Modality::kCamera, Modality::kLidar, Modality::kRadar}) {
      CHECK(files->encoder(m).modality() == m);
      CHECK(files->encoder(m).latent_dim() == 8);
    }
    CHECK(files->heads().paper == (fs::path(dir) / "uavloc.pt").string());
    CHECK(files->heads().anchored.empty());
    const auto edge = files->LoadEdge(false);
    CHECK(edge->latent_dim() == 8);
    CHECK_FALSE(edge->anchored());
    // No anchored head: asking for it names the manifest's key.
    const std::string what = testing::ConfigErrorOf([&] { files->LoadEdge(true); });
    CHECK_THAT(what, Catch::Contains(files->manifest_path()));
    CHECK_THAT(what, Catch::Contains("/anchored_edge"));
    CHECK_THAT(what, Catch::Contains("uavloc_anchored"));
  }
}

TEST_CASE("ModelBundle: each edge head is served by what its sidecar says it is", "[pipeline]") {
  InitTorch(1, 54);
  const std::string dir = ModelFolder("bundle-heads", 8, 8, 8, true);
  auto files = UavLocModelFiles::Load(dir);
  CHECK_FALSE(files->LoadEdge(false)->anchored());
  CHECK(files->LoadEdge(true)->anchored());

  // A model from before the anchored head had its own key: `edge` holds the
  // anchored head, which serves uavloc_anchored; there is no paper head.
  ModelManifest m = ReadModelManifest(dir + "/model.json");
  m.edge = "uavloc_anchored.pt";
  m.anchored_edge = "";
  WriteModelManifest(m, dir + "/model.json");
  files = UavLocModelFiles::Load(dir);
  CHECK(files->heads().paper.empty());
  CHECK(files->heads().anchored == (fs::path(dir) / "uavloc_anchored.pt").string());
  CHECK(files->LoadEdge(true)->anchored());
  CHECK_THAT(testing::ConfigErrorOf([&] { files->LoadEdge(false); }),
             Catch::Contains("no paper head"));

  // Two files of one head: refused, naming both.
  m.edge = "uavloc.pt";
  m.anchored_edge = "uavloc.pt";
  WriteModelManifest(m, dir + "/model.json");
  const std::string what = testing::ConfigErrorOf([&] { UavLocModelFiles::Load(dir); });
  CHECK_THAT(what, Catch::Contains("/anchored_edge"));
  CHECK_THAT(what, Catch::Contains("two edge networks"));
}

TEST_CASE("ModelBundle: Load names the manifest and key of a missing part", "[pipeline]") {
  InitTorch(1, 52);
  const std::string dir = ModelFolder("bundle-missing", 8, 8, 8);
  fs::remove(dir + "/lidar.json");
  std::string what = testing::ConfigErrorOf([&] { UavLocModelFiles::Load(dir); });
  CHECK_THAT(what, Catch::Contains(dir + "/model.json"));
  CHECK_THAT(what, Catch::Contains("/lidar"));
  CHECK_THAT(what, Catch::Contains("lidar.json"));

  const std::string no_edge = ModelFolder("bundle-no-edge", 8, 8, 8);
  fs::remove(no_edge + "/uavloc.pt");
  what = testing::ConfigErrorOf([&] { UavLocModelFiles::Load(no_edge); });
  CHECK_THAT(what, Catch::Contains(no_edge + "/model.json"));
  CHECK_THAT(what, Catch::Contains("/edge"));

  // The weights beside a sidecar, missing or not a LibTorch archive.
  const std::string weights = ModelFolder("bundle-weights", 8, 8, 8);
  fs::remove(weights + "/radar.pt");
  CHECK_THAT(testing::ConfigErrorOf([&] { UavLocModelFiles::Load(weights); }),
             Catch::Contains(weights + "/radar"));
  testing::WriteFile(weights + "/radar.pt", "not a LibTorch archive");
  CHECK_THAT(testing::ConfigErrorOf([&] { UavLocModelFiles::Load(weights); }),
             Catch::Contains(weights + "/radar"));
}

TEST_CASE("ModelBundle: Load refuses parts whose latent size disagrees with the manifest",
          "[pipeline]") {
  InitTorch(1, 53);
  SECTION("the manifest disagrees with every part") {
    const std::string dir = ModelFolder("bundle-z-manifest", 8, 8, 16);
    const std::string what = testing::ConfigErrorOf([&] { UavLocModelFiles::Load(dir); });
    CHECK_THAT(what, Catch::Contains(dir + "/camera.json"));
    CHECK_THAT(what, Catch::Contains("/config/latent_dim"));
  }
  SECTION("the edge network disagrees with the manifest and the encoders") {
    const std::string dir = ModelFolder("bundle-z-edge", 8, 16, 8);
    const std::string what = testing::ConfigErrorOf([&] { UavLocModelFiles::Load(dir); });
    CHECK_THAT(what, Catch::Contains(dir + "/uavloc.pt.json"));
    CHECK_THAT(what, Catch::Contains("/latent_dim"));
  }
  SECTION("a part for another modality") {
    const std::string dir = ModelFolder("bundle-modality", 8, 8, 8);
    ModelManifest m = ReadModelManifest(dir + "/model.json");
    m.camera = "lidar.json";
    WriteModelManifest(m, dir + "/model.json");
    const std::string what = testing::ConfigErrorOf([&] { UavLocModelFiles::Load(dir); });
    CHECK_THAT(what, Catch::Contains(dir + "/lidar.json"));
    CHECK_THAT(what, Catch::Contains("/config/modality"));
  }
}

}  // namespace uavsim::pipeline

namespace uavsim::pipeline {

TEST_CASE("ModelBundle: checksums.sha256 is written over the folder and verified by Load",
          "[pipeline]") {
  InitTorch(1, 53);
  const std::string dir = ModelFolder("bundle-checksums", 8, 8, 8);
  // Without checksums (models of earlier versions): loads unchecked.
  CHECK_NOTHROW(UavLocModelFiles::Load(dir));
  WriteModelChecksums(dir);
  const std::string sums = testing::ReadFile(dir + "/checksums.sha256");
  // sha256sum's format, a line per other file, names sorted.
  CHECK_THAT(sums, Catch::Contains("  camera.json\n"));
  CHECK_THAT(sums, Catch::Contains(core::Sha256FileHex(dir + "/uavloc.pt") + "  uavloc.pt\n"));
  CHECK(sums.find("checksums.sha256") == std::string::npos);
  CHECK(sums.find("  camera.json\n") < sums.find("  model.json\n"));
  CHECK_NOTHROW(UavLocModelFiles::Load(dir));

  // One byte of the edge network's weights changed: refused, naming it.
  std::string weights = testing::ReadFile(dir + "/uavloc.pt");
  const std::string original = weights;
  weights[weights.size() / 2] ^= 1;
  testing::WriteFile(dir + "/uavloc.pt", weights);
  CHECK_THAT(testing::ConfigErrorOf([&] { UavLocModelFiles::Load(dir); }),
             Catch::StartsWith(dir + "/checksums.sha256: uavloc.pt has changed or is corrupted"));
  testing::WriteFile(dir + "/uavloc.pt", original);
  CHECK_NOTHROW(UavLocModelFiles::Load(dir));

  // A listed file that is gone (after the folder's 9 files), and a line
  // that is not "<hex>  <name>".
  testing::WriteFile(dir + "/checksums.sha256", sums + std::string(64, '0') + "  gone.json\n");
  CHECK(testing::ConfigErrorOf([&] { UavLocModelFiles::Load(dir); }) ==
        dir + "/checksums.sha256: line 10: gone.json is missing");
  testing::WriteFile(dir + "/checksums.sha256", "not a digest  uavloc.pt\n");
  CHECK(testing::ConfigErrorOf([&] { UavLocModelFiles::Load(dir); }) ==
        dir + "/checksums.sha256: line 1: expected \"<64 hex digits>  <file name>\"");
}

}  // namespace uavsim::pipeline
