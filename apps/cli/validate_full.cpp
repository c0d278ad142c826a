// `uavsim validate` in the program that loads LibTorch: a trained model is
// checked to the end, loading what only loading checks (a TorchScript
// method's file, a model folder without checksums).
#include "apps/cli/validate.h"
#include "sim/edge_server.h"

namespace uavsim::cli {

int RunValidateCommand(const ParsedArgs& a, int, char**) {
  return ValidateScenarios(a, [](const sim::Scenario& s, const std::string& file, bool quiet) {
    sim::CheckTrainedModel(s, file, quiet);
  });
}

}  // namespace uavsim::cli
