#include "solvers/common/tier.h"

#include "solvers/common/errors.h"

namespace gonogo {

SoilState SoilForTier(const TractionTier& tier, SoilState soil) {
  if (!tier.UsesConeIndex()) soil.cone_index_pa = 0;
  if (!tier.UsesSoilName()) {
    soil.soil_name.clear();
    soil.parameters.reset();
  }
  return soil;
}

void TractionTier::ResolveChoices(TractionRequest& request,
                                  const std::string& field_prefix) const {
  Require(request.surrogate_model.empty(), field_prefix + "surrogate_model",
          "the " + Name() + " tier takes no surrogate model");
  Require(request.surrogate_guard.Empty(), field_prefix + "surrogate_guard",
          "the " + Name() + " tier has no surrogate to guard");
}

void TierRegistry::Register(std::unique_ptr<TractionTier> tier) {
  const std::string name = tier->Name();
  tiers_[name] = std::move(tier);
}

const TractionTier* TierRegistry::Find(const std::string& name) const {
  auto it = tiers_.find(name);
  return it == tiers_.end() ? nullptr : it->second.get();
}

const TractionTier& TierRegistry::Get(const std::string& name) const {
  if (const TractionTier* t = Find(name)) return *t;
  std::string known;
  for (const auto& [n, _] : tiers_) known += (known.empty() ? "" : ", ") + n;
  throw InputError("tier", "unknown tier '" + name + "' (known: " + known + ")");
}

std::vector<std::string> TierRegistry::Names() const {
  std::vector<std::string> names;
  for (const auto& [n, _] : tiers_) names.push_back(n);
  return names;
}

}  // namespace gonogo
