#include "solvers/common/errors.h"

#include <cmath>
#include <cstdio>
#include <exception>

namespace gonogo {

void RequirePlausible(double value, const PlausibleRange& range, const std::string& field) {
  if (std::isfinite(value) && value >= range.min && value <= range.max) return;
  char text[160];
  std::snprintf(text, sizeof text, "%g %s is outside the plausible range [%g, %g] %s", value,
                range.unit, range.min, range.max, range.unit);
  throw InputError(field, text);
}

const char* ErrorKindName(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::kNone: return "no error";
    case ErrorKind::kBadInput: return "bad input";
    case ErrorKind::kCannotCarry: return "soil cannot carry";
    case ErrorKind::kLimit: return "limit exceeded";
    case ErrorKind::kNumerical: return "numerical failure";
    case ErrorKind::kCancelled: return "cancelled";
    case ErrorKind::kInternal: return "internal error";
    case ErrorKind::kPrecondition: return "missing prerequisite";
  }
  return "internal error";
}

ClassifiedError ClassifyCurrentException() {
  try {
    throw;
  } catch (const CannotCarryError& e) {  // before InputError, which it derives from
    return {ErrorKind::kCannotCarry, e.what(), e.field()};
  } catch (const InputError& e) {
    return {ErrorKind::kBadInput, e.what(), e.field()};
  } catch (const LimitError& e) {
    return {ErrorKind::kLimit, e.what(), e.field()};
  } catch (const NumericalError& e) {
    return {ErrorKind::kNumerical, e.what(), ""};
  } catch (const PreconditionError& e) {
    return {ErrorKind::kPrecondition, e.what(), e.field()};
  } catch (const CancelledError& e) {
    return {ErrorKind::kCancelled, e.what(), ""};
  } catch (const std::exception& e) {
    return {ErrorKind::kInternal, e.what(), ""};
  } catch (...) {
    return {ErrorKind::kInternal, "unknown error", ""};
  }
}

void ThrowError(ErrorKind kind, const std::string& field, const std::string& message) {
  switch (kind) {
    case ErrorKind::kBadInput: throw InputError(field, message);
    case ErrorKind::kCannotCarry: throw CannotCarryError(field, message);
    case ErrorKind::kLimit: throw LimitError(field, message);
    case ErrorKind::kNumerical: throw NumericalError(message);
    case ErrorKind::kCancelled: throw CancelledError();
    case ErrorKind::kPrecondition: throw PreconditionError(field, message);
    case ErrorKind::kNone:
    case ErrorKind::kInternal: break;
  }
  throw std::runtime_error(message);
}

}  // namespace gonogo
