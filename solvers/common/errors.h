// Typed errors shared by every layer. Setup and input mistakes throw InputError naming the offending
// field; the server maps it to INVALID_ARGUMENT in one place. Numerical outcomes are returned as values.
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

// Always-on check for input: throws InputError(field, reason) when `ok` is false.
inline void Require(bool ok, const std::string& field, const std::string& reason) {
  if (!ok) throw InputError(field, reason);
}

}  // namespace gonogo
