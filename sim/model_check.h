// The trained models a scenario's methods run, checked without loading
// LibTorch (pipeline/model_resolution.h): what `uavsim validate` does in
// the program that does not load it, and the first half of
// CheckTrainedModel (sim/edge_server.h), which loads what only loading can
// check.
#pragma once

#include <string>

#include "pipeline/model_resolution.h"
#include "sim/hosted_method.h"
#include "sim/scenario.h"

namespace uavsim::sim {

// What the model catalog reads of the scenario (`file`: the name errors give).
pipeline::CatalogScenario CatalogOf(const Scenario& s, const std::string& file);

// Every check of CheckTrainedModel that reads files without loading a
// weight: the Python methods have their functions in `hosted` (null: the
// process's), the model's and its variants' manifests, checksums, heads and
// settings fit. Returns whether loading must finish the check: a
// TorchScript method's file, or a model folder without checksums.sha256.
// Throws core::ConfigError as CheckTrainedModel does.
bool CheckModelFiles(const Scenario& s, const std::string& file,
                     const HostedMethods* hosted = nullptr);

}  // namespace uavsim::sim
