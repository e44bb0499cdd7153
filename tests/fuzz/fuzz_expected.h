// What a fuzz target may see when it feeds untrusted bytes to a parser: the errors the service turns
// into a field-named INVALID_ARGUMENT or RESOURCE_EXHAUSTED. Anything else escaping (another
// exception, a crash, a sanitizer report, a hang) is a finding.
#pragma once

#include "solvers/common/errors.h"

// Runs `body`, swallowing the expected errors.
template <typename Body>
void ExpectOnlyFieldErrors(Body&& body) {
  try {
    body();
  } catch (const gonogo::InputError&) {
  } catch (const gonogo::LimitError&) {
  }
}
