// The classical methods (`ekf`, `anchor_track`) scored on held-out training
// episodes, so that a training report puts them beside the learned heads on
// the same trajectories (issue 19: "every method scored on the same
// windows").
//
// Each episode is replayed as the edge would see it: the samples that
// arrived on time (Sample::on_time, the only ones the heads get), window by
// window in capture order, the modalities of the subset only; after window
// k's samples each method is asked for the target at the window's end,
// k t^w. `ekf` is the run's (MakeEkf of the base scenario: the episodes'
// weather and, on a scenario with `episodes.sizes_m`, their drone size are
// not the base's, and the filter keeps the base's); `anchor_track` gets the
// anchors the samples carry (pipeline/anchored/anchor_track.h). A window
// counts as pipeline::Evaluation says: from the first window in which an
// allowed modality arrived, scored in its part, and answered by the method.
// Deterministic: no randomness.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "pipeline/training/dataset.h"
#include "pipeline/training/trainer.h"
#include "sim/scenario.h"

namespace uavsim::sim {

// By method name ("ekf", "anchor_track"): the seven modality subsets.
// Throws std::invalid_argument for a sample whose node index is not one of
// the scenario's nodes.
std::map<std::string, pipeline::Evaluation> ScoreClassicalMethods(
    const Scenario& base, const std::vector<pipeline::Episode>& episodes);

}  // namespace uavsim::sim
