// `uavsim bench flops`: the paper's Table III (FLOPs of each pre-processing
// step and encoder at a sensing node) as this code base counts it, beside
// the paper's values.
#pragma once

#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace uavsim::sim {

// One table row per module: ours in MFLOPs per frame, the paper's Table III
// value, their ratio (ours / paper) and a note.
//   encoders   counted from the layers' shapes (pipeline/flops.h) of the
//              IbCcModel each layout builds, at the paper's sizes (two
//              128 x 128 crops; 1024 points), z = 16, IB head; 2 FLOPs per
//              multiply-add, the convention that reproduces the paper's
//              147.32 for the image encoder. Rows: the paper's camera layout
//              (two CNN branches, no pool, no ROI geometry), our default
//              camera layout (shared CNN, 4x4 pool, ROI geometry), PointNet
//              for LiDAR (4 channels) and radar (5).
//   pre-processing  ESTIMATES of operations per frame
//              (pipeline/node/preprocess_flops.h) for the default scenario's
//              sensors and pre-processing settings: each labelled
//              "estimate", with its sizes and assumptions.
// Unless `quiet`, the convention, each estimate's stages (operations per
// item x items) and each encoder's parts follow the table. No timing, no
// training; builds the models once (about a second, mostly the paper
// layout's two 16.8 M-weight layers). Returns 0.
// `rows` (if not null) receives the table's rows.
struct FlopsRow {
  std::string module;
  double ours_mflops = 0.0;
  std::optional<double> paper_mflops;  // the paper's Table III value, if it has the row
  std::string note;
};
int BenchFlops(bool quiet, std::ostream& out, std::vector<FlopsRow>* rows = nullptr);

}  // namespace uavsim::sim
