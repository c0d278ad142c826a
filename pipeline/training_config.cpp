#include "pipeline/training_config.h"

namespace uavsim::pipeline {

template <class V>
void Visit(V& v, TrainingConfig& c) {
  using core::Rule;
  v("dropout", c.dropout, Rule{0.0, 1.0, false, true});
  v("beta", c.beta, Rule::NonNegative(1e6));
  v("stage1_lr", c.stage1_lr, Rule::Positive(1.0));
  v("stage1_batch", c.stage1_batch, Rule::Range(2, 1 << 16));
  v("stage1_max_epochs", c.stage1_max_epochs, Rule::NonNegative(1e6));
  v("stage1_patience", c.stage1_patience, Rule::Range(1, 1e6));
  v("stage1_plateau_epochs", c.stage1_plateau_epochs, Rule::NonNegative(1e4));
  v("stage1_min_samples_per_epoch", c.stage1_min_samples_per_epoch, Rule::Range(2, 1e9));
  v("stage1_max_samples_per_epoch", c.stage1_max_samples_per_epoch, Rule::Range(2, 1e9));
  v.Check(c.stage1_max_samples_per_epoch >= c.stage1_min_samples_per_epoch,
          "stage1_max_samples_per_epoch",
          "must be at least stage1_min_samples_per_epoch (" +
              std::to_string(c.stage1_min_samples_per_epoch) + "), got " +
              std::to_string(c.stage1_max_samples_per_epoch));
  v("stage1_max_validation_samples", c.stage1_max_validation_samples, Rule::Range(1, 1e9));
  v("stage1_label_gate_m", c.stage1_label_gate_m, Rule::NonNegative(1e4));
  v("stage1_label_gate_deg", c.stage1_label_gate_deg, Rule::Range(0, 180));
  v("stage2_lr", c.stage2_lr, Rule::Positive(1.0));
  v("stage2_batch", c.stage2_batch, Rule::Range(1, 1 << 16));
  v("stage2_sequence_windows", c.stage2_sequence_windows, Rule::Range(1, 1e6));
  v("stage2_max_epochs", c.stage2_max_epochs, Rule::NonNegative(1e6));
  v("stage2_patience", c.stage2_patience, Rule::Range(1, 1e6));
  v("stage2_plateau_epochs", c.stage2_plateau_epochs, Rule::NonNegative(1e4));
  v("stage2_min_steps_per_epoch", c.stage2_min_steps_per_epoch, Rule::Range(1, 1e9));
  v("modality_dropout", c.modality_dropout, Rule::Probability());
  v("window_dropout", c.window_dropout, Rule::Probability());
  v("d_model", c.d_model, Rule::Range(1, 4096));
  v("layers", c.layers, Rule::Range(1, 64));
  v.Enum("temporal", c.temporal, TemporalKindNames());
  v("mica_lambda_init", c.mica_lambda_init, Rule::Range(-1e3, 1e3));
  v.Enum("te_align_tau_origin", c.te_align_tau_origin,
         std::vector<std::pair<const char*, TauOrigin>>{{"window", TauOrigin::kWindow},
                                                        {"clock", TauOrigin::kClock}});
  v.Enum("alignment", c.alignment, AlignmentNames());
  v("madw", c.madw);
  v("mica", c.mica);
  v.Enum("fusion", c.fusion, FusionKindNames());
  v.Check(c.fusion == FusionKind::kUavLoc || (c.madw && c.mica), "fusion",
          std::string("MADW and MICA belong to the paper's fusion: fusion \"") +
              FusionKindName(c.fusion) + "\" needs madw and mica true");
  v.Enum("camera_stereo_branches", c.camera_stereo_branches,
         std::vector<std::pair<const char*, StereoBranches>>{{"shared", StereoBranches::kShared},
                                                             {"two", StereoBranches::kTwo}});
  v("camera_eye_pool_side", c.camera_eye_pool_side, Rule::Range(0, 32));
  v.Check(
      c.camera_eye_pool_side == 0 || 32 % c.camera_eye_pool_side == 0, "camera_eye_pool_side",
      "expected 0 (no pooling) or a divisor of 32, got " + std::to_string(c.camera_eye_pool_side));
  v("camera_roi_geometry", c.camera_roi_geometry);
  v.Enum("point_frame", c.point_frame, PointFrameNames());
  v.Enum("point_norm", c.point_norm, PointNormNames());
  v.Enum("ib_mse_units", c.ib_mse_units, IbMseUnitsNames());
  v("selection_weight", c.selection_weight, Rule::NonNegative(100));
  v("selection_radius_m", c.selection_radius_m, Rule::Positive(1e4));
  v("filter_preference_m", c.filter_preference_m, Rule::NonNegative(100));
  v("offset_calibration_radius_m", c.offset_calibration_radius_m, Rule::Range(0, 1));
  v.Enum("position_loss", c.mixture_loss,
         std::vector<std::pair<const char*, bool>>{{"mixture", true}, {"mean", false}});
}
UAVSIM_INSTANTIATE_VISIT(TrainingConfig);

TrainingConfig EarlierModelsTrainingConfig() {
  TrainingConfig c;
  c.ib_mse_units = IbMseUnits::kNormalised;
  return c;
}

TrainingConfig TrainingConfigFromJson(const core::Json& doc, const std::string& file,
                                      TrainingConfig defaults) {
  if (!doc.is_object())
    throw core::ConfigError::AboutDocument(file,
                                           "expected an object, got " + core::DescribeValue(doc));
  core::FromJson(doc, file, "", defaults);
  return defaults;
}

core::Json TrainingConfigJson(const TrainingConfig& c) { return core::ToJson(c); }

void CheckTrainingConfig(const TrainingConfig& c, const std::string& file) {
  // The rules live in Visit only: reading the config's own JSON applies them.
  TrainingConfigFromJson(TrainingConfigJson(c), file);
}

}  // namespace uavsim::pipeline
