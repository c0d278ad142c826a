// The training config as data (pipeline/training_config.h): every
// key has a default, the shipped example spells them out, the reader is
// strict and names file, pointer and rule, and the model's manifest records
// the config (and still reads models written without it).
#include <catch2/catch.hpp>
#include <stdexcept>
#include <string>

#include "core/error.h"
#include "core/json_io.h"
#include "pipeline/model_bundle.h"
#include "pipeline/training/trainer.h"
#include "pipeline/training_config.h"
#include "test_support.h"

namespace uavsim::pipeline {
namespace {

using core::Json;

const std::string kExample = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/training/default.json";

// A config with every key away from its default.
TrainingConfig AllChanged() {
  TrainingConfig c;
  c.dropout = 0.25;
  c.beta = 2e-3;
  c.stage1_lr = 3e-4;
  c.stage1_batch = 8;
  c.stage1_max_epochs = 7;
  c.stage1_patience = 2;
  c.stage1_plateau_epochs = 3;
  c.stage1_min_samples_per_epoch = 100;
  c.stage1_max_samples_per_epoch = 200;
  c.stage1_max_validation_samples = 50;
  c.stage1_label_gate_m = 3.5;
  c.stage1_label_gate_deg = 4.5;
  c.stage2_lr = 5e-4;
  c.stage2_batch = 3;
  c.stage2_sequence_windows = 11;
  c.stage2_max_epochs = 9;
  c.stage2_patience = 4;
  c.stage2_plateau_epochs = 0;
  c.stage2_min_steps_per_epoch = 6;
  c.modality_dropout = 0.5;
  c.window_dropout = 0.05;
  c.d_model = 32;
  c.layers = 3;
  c.temporal = TemporalKind::kTcn;
  c.mica_lambda_init = 0.25;
  c.te_align_tau_origin = TauOrigin::kClock;
  c.camera_stereo_branches = StereoBranches::kTwo;
  c.camera_eye_pool_side = 8;
  c.camera_roi_geometry = false;
  c.point_frame = PointFrame::kCentroid;
  c.point_norm = PointNorm::kGroup;
  c.ib_mse_units = IbMseUnits::kNormalised;
  c.selection_weight = 0.5;
  c.selection_radius_m = 1.5;
  c.filter_preference_m = 0.0;
  c.offset_calibration_radius_m = 0.0;
  c.mixture_loss = false;
  c.alignment = Alignment::kMiddle;
  c.madw = false;
  c.mica = false;
  // A fusion baseline needs MADW and MICA on: "fusion" has its own round
  // trip below.
  return c;
}

std::string ErrorOf(const Json& doc) {
  return testing::ConfigErrorOf([&] { TrainingConfigFromJson(doc, "t.json"); });
}

}  // namespace

TEST_CASE("TrainingConfig: {} gives the defaults, and the example spells out exactly them",
          "[pipeline]") {
  const Json defaults = TrainingConfigJson(TrainingConfig{});
  CHECK(TrainingConfigJson(TrainingConfigFromJson(Json::object(), "empty.json")).dump() ==
        defaults.dump());
  CHECK(defaults.at("stage1_lr") == 1e-3);
  CHECK(defaults.at("stage2_plateau_epochs") == 6);
  CHECK(defaults.at("filter_preference_m") == 2.0);
  CHECK(defaults.at("position_loss") == "mixture");
  // The example file: every key, each at its default.
  const Json example = core::LoadJsonFile(kExample);
  CHECK(example.size() == defaults.size());
  for (const auto& [key, value] : defaults.items()) {
    INFO(key);
    REQUIRE(example.contains(key));
    CHECK(example.at(key) == value);
  }
  CHECK(TrainingConfigJson(TrainingConfigFromJson(example, kExample)).dump() == defaults.dump());
}

TEST_CASE("TrainingConfig: a full file round-trips, and absent keys keep the given defaults",
          "[pipeline]") {
  const TrainingConfig changed = AllChanged();
  const Json j = TrainingConfigJson(changed);
  const Json defaults = TrainingConfigJson(TrainingConfig{});
  // Every key differs from its default, so the round trip proves each is read
  // (fusion: see below).
  for (const auto& [key, value] : defaults.items()) {
    INFO(key);
    if (key != "fusion") CHECK(j.at(key) != value);
  }
  for (const FusionKind f : {FusionKind::kEarly, FusionKind::kLate, FusionKind::kHemis}) {
    TrainingConfig c;
    c.fusion = f;
    CHECK(TrainingConfigFromJson(TrainingConfigJson(c), "f.json").fusion == f);
  }
  const std::string dir = testing::TempDir("training-config");
  testing::WriteFile(dir + "/t.json", j.dump(2));
  const TrainingConfig back =
      TrainingConfigFromJson(core::LoadJsonFile(dir + "/t.json"), dir + "/t.json");
  CHECK(TrainingConfigJson(back).dump() == j.dump());
  CHECK_FALSE(back.mixture_loss);

  // Reading over other defaults (as --quick does) changes only the keys given.
  TrainingConfig base;
  base.stage1_lr = 2e-3;
  base.stage2_max_epochs = 40;
  const TrainingConfig over =
      TrainingConfigFromJson(Json{{"stage2_max_epochs", 12}}, "q.json", base);
  CHECK(over.stage1_lr == 2e-3);
  CHECK(over.stage2_max_epochs == 12);
}

TEST_CASE("TrainingConfig: unknown keys and bad values name the file, pointer, value and rule",
          "[pipeline]") {
  CHECK(ErrorOf(Json{{"fusion", "hemis"}, {"mica", false}}) ==
        "t.json: /fusion: MADW and MICA belong to the paper's fusion: fusion \"hemis\" needs "
        "madw and mica true");
  CHECK_THAT(ErrorOf(Json{{"alignment", "last"}}), Catch::StartsWith("t.json: /alignment: "));
  CHECK(ErrorOf(Json{{"stage1_lrr", 1e-3}}) ==
        "t.json: /stage1_lrr: unknown key (did you mean \"stage1_lr\"?)");
  CHECK(ErrorOf(Json{{"filter_preference", 1}}) ==
        "t.json: /filter_preference: unknown key (did you mean \"filter_preference_m\"?)");
  CHECK(ErrorOf(Json{{"offset_calibration_radius_m", 1.5}}) ==
        "t.json: /offset_calibration_radius_m: expected a number in [0, 1], got 1.5");
  CHECK(ErrorOf(Json{{"selection_weight", -1}}) ==
        "t.json: /selection_weight: expected a number in [0, 100], got -1");
  CHECK(ErrorOf(Json{{"stage2_plateau_epochs", 2.5}}) ==
        "t.json: /stage2_plateau_epochs: expected an integer in [0, 10000], got 2.5");
  CHECK(ErrorOf(Json{{"stage1_lr", 0}}) ==
        "t.json: /stage1_lr: expected a number in (0, 1], got 0");
  CHECK(ErrorOf(Json{{"stage1_label_gate_deg", 200}}) ==
        "t.json: /stage1_label_gate_deg: expected a number in [0, 180], got 200");
  CHECK_THAT(ErrorOf(Json{{"position_loss", "l1"}}),
             Catch::StartsWith("t.json: /position_loss: expected one of \"mixture\", \"mean\""));
  CHECK_THAT(ErrorOf(Json{{"stage1_lr", "fast"}}), Catch::StartsWith("t.json: /stage1_lr: "));
  CHECK(
      ErrorOf(Json{{"stage1_min_samples_per_epoch", 500}, {"stage1_max_samples_per_epoch", 400}}) ==
      "t.json: /stage1_max_samples_per_epoch: must be at least stage1_min_samples_per_epoch "
      "(500), got 400");
  CHECK_THAT(ErrorOf(Json::array()), Catch::StartsWith("t.json: "));
  CHECK_THAT(
      ErrorOf(Json{{"camera_stereo_branches", "three"}}),
      Catch::StartsWith("t.json: /camera_stereo_branches: expected one of \"shared\", \"two\""));
  CHECK(ErrorOf(Json{{"camera_eye_pool_side", 3}}) ==
        "t.json: /camera_eye_pool_side: expected 0 (no pooling) or a divisor of 32, got 3");
  CHECK_THAT(ErrorOf(Json{{"temporal", "transformer"}}),
             Catch::StartsWith(
                 "t.json: /temporal: expected one of \"mamba\", \"gru\", \"lstm\", \"tcn\""));
  CHECK_THAT(ErrorOf(Json{{"camera_roi_geometry", 1}}),
             Catch::StartsWith("t.json: /camera_roi_geometry: "));

  // The same rules guard TrainOptions built in code.
  TrainOptions o;
  CHECK_NOTHROW(o.Validate());
  o.window_dropout = 1.5;
  CHECK_THROWS_WITH(o.Validate(), Catch::Contains("/window_dropout") &&
                                      Catch::Contains("expected a number in [0, 1], got 1.5"));
  o = TrainOptions{};
  o.latent_dim = 3;
  CHECK_THROWS_AS(o.Validate(), std::invalid_argument);
}

TEST_CASE("TrainingConfig: the paper's preset sets what Sec. VI and Sec. IV-B give", "[pipeline]") {
  const std::string file = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/training/paper.json";
  const TrainingConfig paper = TrainingConfigFromJson(core::LoadJsonFile(file), file);
  // Sec. VI: learning rate 1e-4, beta 1e-3, lambda 0.5, dropout 0.1.
  CHECK(paper.stage1_lr == 1e-4);
  CHECK(paper.stage2_lr == 1e-4);
  CHECK(paper.beta == 1e-3);
  CHECK(paper.mica_lambda_init == 0.5);
  CHECK(paper.dropout == 0.1);
  // Sec. V-A, Eq. (19): tau is the frame's time stamp.
  CHECK(paper.te_align_tau_origin == TauOrigin::kClock);
  // Sec. IV-B: two parallel CNN branches; Table III's count: no pool, and
  // the crop alone.
  CHECK(paper.camera_stereo_branches == StereoBranches::kTwo);
  CHECK(paper.camera_eye_pool_side == 0);
  CHECK_FALSE(paper.camera_roi_geometry);
}

TEST_CASE("ModelManifest: records the training config, and reads models without one",
          "[pipeline]") {
  const std::string dir = testing::TempDir("manifest-training");
  ModelManifest m;
  m.note = "with config";
  m.training = AllChanged();
  WriteModelManifest(m, dir + "/model.json");
  const Json raw = Json::parse(testing::ReadFile(dir + "/model.json"));
  CHECK(raw.at("training").dump() == TrainingConfigJson(AllChanged()).dump());
  const ModelManifest back = ReadModelManifest(dir + "/model.json");
  REQUIRE(back.training.has_value());
  CHECK(TrainingConfigJson(*back.training).dump() == TrainingConfigJson(AllChanged()).dump());

  // Written before the config existed: no block, and none invented.
  ModelManifest old;
  WriteModelManifest(old, dir + "/old.json");
  CHECK_FALSE(Json::parse(testing::ReadFile(dir + "/old.json")).contains("training"));
  CHECK_FALSE(ReadModelManifest(dir + "/old.json").training.has_value());
  // A block written before a key existed reads that key as what such models
  // were trained with, not as today's default: ib_mse_units "normalised".
  Json earlier = TrainingConfigJson(TrainingConfig{});
  earlier.erase("ib_mse_units");
  testing::WriteFile(dir + "/earlier.json",
                     Json{{"format", "uavsim-model/1"}, {"training", earlier}}.dump(2));
  const ModelManifest earlier_back = ReadModelManifest(dir + "/earlier.json");
  REQUIRE(earlier_back.training.has_value());
  CHECK(earlier_back.training->ib_mse_units == IbMseUnits::kNormalised);
  CHECK(TrainingConfig{}.ib_mse_units == IbMseUnits::kMetres);
  // The shipped model was trained with the defaults but for the keys its
  // command sets (docs/methods-and-models.md: point_frame centroid, point_norm
  // none, the stage-1 label gate at 3 m, stage 1 up to 300 epochs with
  // patience 20 and the step halved after 5, no dropout, stage 2 on crops of
  // 100 windows), and says so.
  const ModelManifest shipped = ReadModelManifest(DefaultModelPath());
  REQUIRE(shipped.training.has_value());
  TrainingConfig expected;
  expected.point_frame = PointFrame::kCentroid;
  expected.point_norm = PointNorm::kNone;
  expected.stage1_label_gate_m = 3.0;
  expected.stage1_max_epochs = 300;
  expected.stage1_patience = 20;
  expected.stage1_plateau_epochs = 5;
  expected.dropout = 0.0;
  expected.stage2_sequence_windows = 100;
  CHECK(TrainingConfigJson(*shipped.training).dump() == TrainingConfigJson(expected).dump());

  // The block is read as strictly as a config file.
  testing::WriteFile(dir + "/bad.json",
                     "{\"format\": \"uavsim-model/1\", \"training\": {\"layer\": 3}}\n");
  CHECK(testing::ConfigErrorOf([&] { ReadModelManifest(dir + "/bad.json"); }) ==
        dir + "/bad.json: /training/layer: unknown key (did you mean \"layers\"?)");
}

}  // namespace uavsim::pipeline
