// libFuzzer target: a scenario file's text through the whole strict loader
// (ParseJsonText, then ScenarioFromJson with the shipped scenarios' folder,
// so their relative mesh and model paths resolve). A scenario the loader
// accepts must also accept its own resolved form and resolve to the same
// document (what `run` writes as resolved.json is a valid scenario).
#include <cstddef>
#include <cstdint>

#include "core/json_io.h"
#include "fuzz_support.h"
#include "sim/scenario.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace uavsim;
  fuzz::RunLoader(data, size, [](const std::string& text) {
    const core::Json doc = core::ParseJsonText(text, "fuzz.json");
    const sim::Scenario s = sim::ScenarioFromJson(doc, "fuzz.json", UAVSIM_SCENARIOS_DIR);
    const core::Json resolved = sim::ResolvedJson(s);
    core::Json again;
    try {
      again = sim::ResolvedJson(sim::ScenarioFromJson(resolved, "resolved.json", s.base_dir));
    } catch (const core::ConfigError& e) {
      fuzz::Finding("the resolved scenario is refused", e.what());
    }
    if (again != resolved)
      fuzz::Finding("the resolved scenario resolves differently", resolved.dump());
  });
  return 0;
}
