// Configuration of one modality's IB-CC model (paper Sec. IV-B, Table I):
// which feature encoder, the latent size z, the bottleneck (the paper's
// variational IB head, or its MLP baseline of equal depth and parameter
// count), the training constants and the input normalisation. Plain data,
// torch-free; saved beside trained weights as a JSON sidecar.
#pragma once

#include "pipeline/node/ib_normalization.h"
#include "pipeline/node/observations.h"

namespace uavsim::pipeline {

enum class IbBottleneck {
  kIb,   // mu and sigma MLPs, reparameterisation, KL term (the paper's IB-CC)
  kMlp,  // deterministic MLP of the same depth and parameter count, no KL (Sec. VI baseline)
};

struct IbCcConfig {
  Modality modality = Modality::kCamera;  // camera: image encoder; lidar/radar: PointNet
  int latent_dim = 16;                    // paper: z in {4, 8, 16, 32, 64}
  IbBottleneck bottleneck = IbBottleneck::kIb;
  double dropout = 0.1;  // paper Sec. VI
  double beta = 1e-3;    // paper Sec. VI: IB trade-off in L = MSE + beta KL
  IbNormalization normalization;
};

template <class V>
void Visit(V& v, IbCcConfig& c);

}  // namespace uavsim::pipeline
