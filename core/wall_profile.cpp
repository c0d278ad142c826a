#include "core/wall_profile.h"

#include <algorithm>

namespace uavsim::core {

WallProfile::Part& WallProfile::part(const std::string& name) {
  if (auto it = by_name_.find(name); it != by_name_.end()) return *it->second;
  parts_.push_back(Part{name, 0.0});
  by_name_.emplace(name, &parts_.back());
  return parts_.back();
}

std::vector<std::pair<std::string, double>> WallProfile::parts() const {
  std::vector<std::pair<std::string, double>> out;
  out.reserve(parts_.size());
  for (const Part& p : parts_) out.emplace_back(p.name, p.seconds);
  return out;
}

std::vector<std::pair<std::string, double>> WallProfile::Top(std::size_t n) const {
  std::vector<std::pair<std::string, double>> out = parts();
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  if (out.size() > n) out.resize(n);
  return out;
}

double WallProfile::total_s() const {
  double sum = 0.0;
  for (const Part& p : parts_) sum += p.seconds;
  return sum;
}

}  // namespace uavsim::core
