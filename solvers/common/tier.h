// The traction-tier interface and its registry. A tier is added by writing one class and one line in
// RegisterBuiltinTiers(); nothing else is edited (CONVENTIONS: no static self-registration).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "solvers/common/traction.h"

namespace gonogo {

// Returns true once the caller no longer wants the answer (job cancelled, server draining).
using CancelCheck = std::function<bool()>;

// Thrown by a tier that noticed a cancellation part-way through.
class CancelledError : public std::runtime_error {
 public:
  CancelledError() : std::runtime_error("cancelled") {}
};

class TractionTier {
 public:
  virtual ~TractionTier() = default;
  virtual std::string Name() const = 0;
  // Bumped whenever the numbers a tier returns could change; part of every cache key.
  virtual std::string Version() const = 0;
  // Which parts of a SoilState the tier reads. What it does not read is stripped before planning
  // and keying (SoilForTier), so that it neither splits terrain units nor cache keys.
  virtual bool UsesConeIndex() const { return true; }
  // The soil name and explicit Bekker parameters.
  virtual bool UsesSoilName() const { return false; }
  // Checks, before any work is queued, that the tier can resolve this soil (library name, explicit
  // parameters); throws InputError naming `field`. Cheap: no solver work.
  virtual void ValidateSoil(const SoilState& /*soil*/, const std::string& /*field*/) const {}
  // Computes one curve. Throws InputError for requests the tier cannot take; thread-safe.
  virtual TractionCurve Compute(const TractionRequest& request) const = 0;
  // As Compute(), polling `cancelled` where the tier can stop early. Tiers whose curves take
  // microseconds keep this default, which checks once before starting.
  virtual TractionCurve Compute(const TractionRequest& request, const CancelCheck& cancelled) const {
    if (cancelled && cancelled()) throw CancelledError();
    return Compute(request);
  }
};

// The soil with only the parts `tier` reads.
SoilState SoilForTier(const TractionTier& tier, SoilState soil);

class TierRegistry {
 public:
  void Register(std::unique_ptr<TractionTier> tier);
  // nullptr when no tier has that name.
  const TractionTier* Find(const std::string& name) const;
  // Throws InputError("tier", ...) listing the known tiers.
  const TractionTier& Get(const std::string& name) const;
  std::vector<std::string> Names() const;

 private:
  std::map<std::string, std::unique_ptr<TractionTier>> tiers_;
};

}  // namespace gonogo
