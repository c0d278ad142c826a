// The paper's Sec. VI baselines and ablations as named variants of the
// trained pipeline (`uavsim train --variant NAME`). A variant is data: the
// training-config keys it sets (applied over the defaults, before any
// --config file or --config-set, and checked by the same rules), plus the
// node-side choices a training config does not hold (the MLP bottleneck, raw
// pre-processing). Its model folder records the name (model.json
// "variant"); in the loop it runs as the method of that name (VariantMethod).
//
// The names are a contract (docs/training.md, docs/variants.md): paper (the default), gru, lstm,
// tcn, te_align, resample_first, resample_middle, resample_random, no_madw, no_mica, no_madw_mica,
// early_fusion, late_fusion, modality_dropout, hemis, mlp_bottleneck, raw, raw_camera,
// raw_lidar_radar, raw_gru, raw_lstm, raw_tcn. Torch-free header.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "pipeline/training_config.h"

namespace uavsim::pipeline {

struct Variant {
  const char* name;
  const char* figure;       // the paper's artefact it belongs to
  const char* description;  // one line for --help and docs/training.md
  const char* config;       // JSON object of TrainingConfig keys it sets
  bool mlp_bottleneck;      // the nodes compress with the MLP baseline
  // The modalities whose nodes encode raw (not pre-processed) data: bit m
  // for Modality m (1 camera, 2 LiDAR, 4 radar); 0: all pre-processed.
  std::uint8_t raw_modalities;
};

// Whether a model of variant `a` can lend its stage-1 encoders to a training
// of variant `b`: their nodes send the same latents (same bottleneck, same
// raw modalities).
bool SameNodes(const Variant& a, const Variant& b);

// Every variant, `paper` first.
const std::vector<Variant>& Variants();
// nullptr when `name` is none of them.
const Variant* FindVariant(const std::string& name);
// "paper, gru, lstm, ..." for messages.
std::string VariantNames();
// The method name a variant runs under: "uavloc" for paper, else its name.
std::string VariantMethod(const std::string& name);

// `base` with the variant's keys set. Throws core::ConfigError naming
// "variant NAME" and the key when the variant's keys break a rule.
TrainingConfig ApplyVariant(const Variant& v, const TrainingConfig& base);

}  // namespace uavsim::pipeline
