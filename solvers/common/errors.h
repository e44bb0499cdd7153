// Typed errors shared by every layer. Setup and input mistakes throw InputError naming the offending
// field; a solver that cannot answer valid input throws NumericalError. Every error keeps its kind
// (ErrorKind) across threads, ranks and RPCs and becomes a gRPC status in one place
// (server/status.h): INVALID_ARGUMENT only for bad input.
#pragma once

#include <stdexcept>
#include <string>

namespace gonogo {

// Something the caller got wrong: names the field and the reason.
class InputError : public std::invalid_argument {
 public:
  InputError(std::string field, const std::string& reason)
      : std::invalid_argument(field + ": " + reason), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

// The soil cannot carry the wheel (it would sink past its axle). A solver throws it; a tier turns it
// into an immobile TractionCurve, because for a map this is an answer (NO-GO), not a failure.
class CannotCarryError : public InputError {
 public:
  using InputError::InputError;
};

// A request that exceeds a configured limit (maps to RESOURCE_EXHAUSTED).
class LimitError : public std::runtime_error {
 public:
  LimitError(std::string field, const std::string& reason)
      : std::runtime_error(field + ": " + reason), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

// A solver could not answer a valid request: an element turned inside out, an iteration did not
// converge, a state went non-finite. Retrying the same request gives the same failure; other
// solver settings (a finer mesh, a smaller step) may not. Maps to FAILED_PRECONDITION.
class NumericalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The request is valid but the service lacks what it needs to answer it (e.g. no surrogate model
// is registered for the soil): names the field and what would provide it. Maps to
// FAILED_PRECONDITION.
class PreconditionError : public std::runtime_error {
 public:
  PreconditionError(std::string field, const std::string& reason)
      : std::runtime_error(field + ": " + reason), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

// Thrown by a solver that noticed a cancellation part-way through.
class CancelledError : public std::runtime_error {
 public:
  CancelledError() : std::runtime_error("cancelled") {}
};

// What went wrong, as it crosses threads, MPI ranks and RPCs. The values are part of the worker
// wire format (proto/gonogo/v1/worker.proto): append, never renumber.
enum class ErrorKind : int {
  kNone = 0,         // no error
  kBadInput = 1,     // InputError: the caller's mistake, names the field
  kCannotCarry = 2,  // CannotCarryError: the soil cannot carry the wheel
  kLimit = 3,        // LimitError: a configured limit
  kNumerical = 4,    // NumericalError: the solver could not answer valid input
  kCancelled = 5,    // CancelledError: the caller no longer wants the answer
  kInternal = 6,     // anything else: a defect or an environment failure
  kPrecondition = 7,  // PreconditionError: something the request needs is missing, names the field
};

// "bad input", "soil cannot carry", ... for messages and logs.
const char* ErrorKindName(ErrorKind kind);

// The kind and message of the exception being handled; call only inside a catch block.
struct ClassifiedError {
  ErrorKind kind = ErrorKind::kInternal;
  std::string message;
  std::string field;  // for kBadInput, kCannotCarry, kLimit and kPrecondition: the field named
};
ClassifiedError ClassifyCurrentException();

// Throws the exception class of `kind` (InputError for kBadInput, ...) with `message`: how an error
// that crossed a rank boundary as a value is raised again with its kind. `field` names the field for
// the kinds that carry one (their message becomes "field: message"); for the others it is ignored.
[[noreturn]] void ThrowError(ErrorKind kind, const std::string& field, const std::string& message);

// Always-on check for input: throws InputError(field, reason) when `ok` is false.
inline void Require(bool ok, const std::string& field, const std::string& reason) {
  if (!ok) throw InputError(field, reason);
}

// The widest values an input can plausibly take, declared beside the parameter it bounds. A value
// outside is a unit mistake (or an attack) and is refused when the request arrives, so that nothing
// accepted fails later for a reason known at submission.
struct PlausibleRange {
  double min;
  double max;
  const char* unit;
};

// InputError naming `field`, the value and the range when `value` is not finite or lies outside.
void RequirePlausible(double value, const PlausibleRange& range, const std::string& field);

}  // namespace gonogo
