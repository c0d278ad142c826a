// Configuration of one modality's IB-CC model (paper Sec. IV-B, Table I):
// which feature encoder, the latent size z, the bottleneck (the paper's
// variational IB head, or its MLP baseline of equal depth and parameter
// count), the training constants and the input normalisation. Plain data,
// torch-free; saved beside trained weights as a JSON sidecar.
#pragma once

#include <utility>
#include <vector>

#include "pipeline/node/ib_normalization.h"
#include "pipeline/node/observations.h"

namespace uavsim::pipeline {

enum class IbBottleneck {
  kIb,   // mu and sigma MLPs, reparameterisation, KL term (the paper's IB-CC)
  kMlp,  // deterministic MLP of the same depth and parameter count, no KL (Sec. VI baseline)
};

// How the camera's feature encoder treats the two stereo eyes (Table I).
enum class StereoBranches {
  kShared,  // one CNN runs on both eyes (ours: half the weights)
  kTwo,     // two parallel CNN branches, one per eye (the paper, Sec. IV-B)
};

// The frame the PointNet sees a cloud's points in (LiDAR and radar).
enum class PointFrame {
  kScene,     // normalised scene coordinates as they are (the paper)
  kCentroid,  // relative to the cloud's centroid, the centroid joined to the
              // pooled feature (ours: translation-equivariant features)
};

// The normalisation after each of the PointNet's convolutions.
enum class PointNorm {
  kBatch,  // BatchNorm over the batch's points (Table I, the paper)
  kGroup,  // GroupNorm of each point's channels, 8 groups (ours)
  kNone,   // none; the convolutions get a bias (ours)
};

// The units of L_MSE in L = L_MSE + beta D_KL (IbCcModelImpl::Loss). The
// network's positions are normalised (ib_normalization.h); the units decide
// how much beta weighs: a latent coordinate whose noise sigma costs sigma^2
// of L_MSE and about -beta log sigma of D_KL settles at sigma^2 = beta / 2,
// i.e. sqrt(beta / 2) m per axis in metres, sqrt(beta / 2) * scale_m in
// normalised units.
enum class IbMseUnits {
  kMetres,      // the position's squared error in m^2 (the paper's equation with y in metres)
  kNormalised,  // in units of the scene's scale_m (ours: beta weighs scale_m^2 more)
};

struct IbCcConfig {
  Modality modality = Modality::kCamera;  // camera: image encoder; lidar/radar: PointNet
  int latent_dim = 16;                    // paper: z in {4, 8, 16, 32, 64}
  IbBottleneck bottleneck = IbBottleneck::kIb;
  double dropout = 0.1;  // paper Sec. VI
  double beta = 1e-3;    // paper Sec. VI: IB trade-off in L = MSE + beta KL
  // Training only; the default is what models trained before the key used
  // (a sidecar without it loads as before).
  IbMseUnits mse_units = IbMseUnits::kNormalised;
  IbNormalization normalization;
  // Camera only; the defaults are the layout of models trained before these
  // switches existed (a sidecar without the keys loads as before). The
  // paper's design: kTwo, 0, false (scenarios/training/paper.json).
  StereoBranches stereo_branches = StereoBranches::kShared;
  // Side of the average pool of each eye's 64x32x32 map before the bottleneck
  // (a divisor of 32): 4 keeps 64x4x4 = 1 024 features an eye (ours); 0 pools
  // nothing, 65 536 features an eye (the paper's Table III count).
  int eye_pool_side = 4;
  // Append the crop's 18 ROI-geometry features (where it lies in the image,
  // ib_normalization.h) to h^c (ours); the paper's 128x128 crop alone carries
  // no bearing.
  bool roi_geometry = true;
  // LiDAR and radar only; the defaults are the paper's design and the layout
  // of models trained before these switches existed.
  PointFrame point_frame = PointFrame::kScene;
  PointNorm point_norm = PointNorm::kBatch;
};

// "scene" / "centroid"; "batch" / "group" / "none"; "metres" / "normalised".
const char* PointFrameName(PointFrame f);
const char* PointNormName(PointNorm n);
const std::vector<std::pair<const char*, PointFrame>>& PointFrameNames();
const std::vector<std::pair<const char*, PointNorm>>& PointNormNames();
const char* IbMseUnitsName(IbMseUnits u);
const std::vector<std::pair<const char*, IbMseUnits>>& IbMseUnitsNames();

template <class V>
void Visit(V& v, IbCcConfig& c);

}  // namespace uavsim::pipeline
