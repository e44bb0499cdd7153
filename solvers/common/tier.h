// The traction-tier interface and its registry. A tier is added by writing one adapter class under
// solvers/tiers/ and one line in RegisterBuiltinTiers(); nothing else is edited (CONVENTIONS: no
// static self-registration). solvers/tiers/README.md walks through it.
#pragma once

#include <mpi.h>

#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "solvers/common/errors.h"
#include "solvers/common/traction.h"

namespace gonogo {

// Returns true once the caller no longer wants the answer (job cancelled, server draining).
using CancelCheck = std::function<bool()>;

// Fraction of the curve done, in [0, 1]; called now and then, never required.
using ProgressReport = std::function<void(double fraction)>;

// What one Compute call is given besides the request.
struct ComputeContext {
  // May be empty. In a collective task (communicator set) the call is collective on the
  // communicator: every rank of the group must call it at the same points, and all get the same
  // answer.
  CancelCheck cancelled;
  ProgressReport progress;  // may be empty; in a collective task only the group's rank 0 reports
  int threads = 1;          // threads the tier may use inside this call (OpenMP or std::thread)
  // The task's rank group, for a tier whose Needs().ranks > 1: Compute is then collective on it and
  // its group rank 0 returns the curve (the other ranks' return values are discarded).
  // MPI_COMM_NULL when the task runs on one rank or in a process without MPI: the tier computes
  // alone.
  MPI_Comm communicator = MPI_COMM_NULL;
  // An existing directory, private to this request (the same one when the same request is run
  // again, after a restart), where a long tier may keep restart files and resume from them;
  // empty: no checkpoints. On every rank of a group it names the same directory (a file system
  // the group shares).
  std::string checkpoint_dir;
  // Where a tier hands on what it computed besides its curve that a surrogate can learn from (the
  // fe-ann tier: its fallen-back points' paths on their RVEs, as SerializeHistory bytes,
  // solvers/ann/strain_history.h), called once at the end of the computation, also when it stops
  // early; empty: nothing is kept (and nothing recorded for it).
  std::function<void(std::vector<std::string> histories)> keep_training_histories;
  // A tier's word on how its run goes, beside the fraction (the fe-ann tier: its points fallen
  // back to their RVEs so far), called before the progress report it goes with; may be empty. In a
  // collective task only the group's rank 0 reports.
  std::function<void(const std::string& note)> progress_note;

  bool Cancelled() const { return cancelled && cancelled(); }
  void Report(double fraction) const {
    if (progress) progress(fraction);
  }
};

// What a tier asks of the pool for one request (ARCHITECTURE section 5).
struct TierNeeds {
  int ranks = 1;                // MPI ranks of one task; > 1 makes the task collective
  int threads = 1;              // threads per rank it can use
  double expected_seconds = 0;  // typical cost of this request, for scheduling (cheap vs long)
};

// Human-facing description for `gonogo tiers`.
struct TierDescription {
  std::string summary;       // one line: the model
  std::string reads;         // which parts of the soil state and tyre it reads
  std::string typical_cost;  // e.g. "microseconds", "minutes on one core"
  // Soil models (solvers/common/soil_model.h) whose parameter sets, explicit or by catalogue
  // name, the tier reads; empty for a tier that reads only the cone index.
  std::vector<std::string> soil_models;
};

class TractionTier {
 public:
  virtual ~TractionTier() = default;
  virtual std::string Name() const = 0;
  // Bumped whenever the numbers a tier returns could change; part of every cache key.
  virtual std::string Version() const = 0;
  // The version of the curve a request (as ResolveChoices leaves it) computes, which the key
  // carries: Version(), or, on a tier whose options a request may set (fe-ann: its surrogate
  // guard), the version of the options the request sets.
  virtual std::string VersionFor(const TractionRequest& /*request*/) const { return Version(); }
  virtual TierDescription Describe() const = 0;
  // Resources of one request; the default is one rank, one thread, negligible time.
  virtual TierNeeds Needs(const TractionRequest& /*request*/) const { return {}; }
  // Which parts of a SoilState the tier reads. What it does not read is stripped before planning
  // and keying (SoilForTier), so that it neither splits terrain units nor cache keys.
  virtual bool UsesConeIndex() const { return true; }
  // The soil name and explicit soil-model parameters.
  virtual bool UsesSoilName() const { return false; }
  // Checks, before any work is queued, that the tier can resolve this soil (library name, explicit
  // parameters); throws InputError naming `field`. Cheap: no solver work.
  virtual void ValidateSoil(const SoilState& /*soil*/, const std::string& /*field*/) const {}
  // Makes the request definite before it is keyed: a tier that chooses something on the request's
  // behalf (fe-ann: the surrogate model, when none is named) writes its choice into the request,
  // so that the cache key says what was computed; likewise the whole surrogate guard, when the
  // request sets part of it. Throws InputError naming field_prefix + "surrogate_model" for a
  // model the tier does not take or know (+ "surrogate_guard" for a guard it does not take),
  // PreconditionError when it has nothing to answer with. Cheap. Default: the request may name
  // no surrogate model and set no guard.
  virtual void ResolveChoices(TractionRequest& request, const std::string& field_prefix) const;

  // Computes one curve: throws CancelledError when the tier notices `context` cancelled during the
  // work, InputError for requests the tier cannot take, NumericalError when the solver fails on a
  // valid request; returns an immobile curve when the soil cannot carry the wheel. Thread-safe.
  TractionCurve Compute(const TractionRequest& request, const ComputeContext& context) const {
    return ComputeCurve(request, context);
  }
  TractionCurve Compute(const TractionRequest& request) const {
    return Compute(request, ComputeContext{});
  }
  TractionCurve Compute(const TractionRequest& request, const CancelCheck& cancelled) const {
    ComputeContext context;
    context.cancelled = cancelled;
    return Compute(request, context);
  }

 protected:
  // The tier's work. Tiers whose curves take microseconds may ignore `context`; long ones poll
  // context.Cancelled() and call context.Report().
  virtual TractionCurve ComputeCurve(const TractionRequest& request,
                                     const ComputeContext& context) const = 0;
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
