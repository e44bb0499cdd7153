// The one place where an error becomes a gRPC status (CONVENTIONS "Errors"). Every layer throws or
// carries a typed error (solvers/common/errors.h: ErrorKind); handlers return StatusFor/ToStatus.
//
//   bad input            INVALID_ARGUMENT     (the message names the field)
//   soil cannot carry    INVALID_ARGUMENT     (a single-wheel query whose load the soil cannot bear;
//                                              in a map it is an answer, NO-GO, never an error)
//   limit exceeded       RESOURCE_EXHAUSTED
//   numerical failure    FAILED_PRECONDITION  (valid input the solver could not answer)
//   cancelled            CANCELLED
//   internal, database   INTERNAL
#pragma once

#include <grpcpp/grpcpp.h>

#include <exception>
#include <string>

#include "solvers/common/errors.h"

namespace gonogo::server {

grpc::StatusCode CodeFor(ErrorKind kind);
grpc::Status StatusFor(ErrorKind kind, const std::string& message);
// The status of a thrown exception (classified with ClassifyCurrentException).
grpc::Status ToStatus(const std::exception_ptr& error);

}  // namespace gonogo::server
