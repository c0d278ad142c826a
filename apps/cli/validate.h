// `uavsim validate`: checks scenarios strictly and says what a run of each
// would cost here. Its body is shared by the two programs (cli.h), which
// differ in how far they check a trained model: uavsim-main loads what only
// loading checks (validate_full.cpp), uavsim-light checks the files and
// hands a scenario that needs more to uavsim-main (light_main.cpp).
#pragma once

#include <functional>
#include <string>

#include "apps/cli/cli.h"
#include "sim/scenario.h"

namespace uavsim::cli {

// Checks the trained models scenario `s` (from `file`) runs; `quiet`: no
// warnings. Throws core::ConfigError.
using ModelCheck = std::function<void(const sim::Scenario& s, const std::string& file, bool quiet)>;

// validate's body: each positional scenario file loaded, checked (its models
// by `check_models`) and its line printed; exit code 0 or 2.
int ValidateScenarios(const ParsedArgs& a, const ModelCheck& check_models);

}  // namespace uavsim::cli
