#include "sim/model_check.h"

namespace uavsim::sim {

pipeline::CatalogScenario CatalogOf(const Scenario& s, const std::string& file) {
  pipeline::CatalogScenario c;
  c.pipeline = &s.pipeline;
  c.base_dir = s.base_dir;
  c.file = file;
  c.layout_hash = LayoutHash(s);
  return c;
}

bool CheckModelFiles(const Scenario& s, const std::string& file, const HostedMethods* hosted) {
  CheckHostedMethods(s, file, hosted);
  const pipeline::ModelResolution r = pipeline::ResolveModels(CatalogOf(s, file));
  if (!r.needs_model) return false;
  for (const std::string& method : s.pipeline.methods)
    if (s.pipeline.FindScripted(method)) return true;
  return !r.unchecked.empty();
}

}  // namespace uavsim::sim
