#include "server/status.h"

#include "cache/database.h"

namespace gonogo::server {

grpc::StatusCode CodeFor(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::kNone: return grpc::StatusCode::OK;
    case ErrorKind::kBadInput:
    case ErrorKind::kCannotCarry: return grpc::StatusCode::INVALID_ARGUMENT;
    case ErrorKind::kLimit: return grpc::StatusCode::RESOURCE_EXHAUSTED;
    case ErrorKind::kNumerical:
    case ErrorKind::kPrecondition: return grpc::StatusCode::FAILED_PRECONDITION;
    case ErrorKind::kCancelled: return grpc::StatusCode::CANCELLED;
    case ErrorKind::kInternal: break;
  }
  return grpc::StatusCode::INTERNAL;
}

grpc::Status StatusFor(ErrorKind kind, const std::string& message) {
  if (kind == ErrorKind::kNone) return grpc::Status::OK;
  return grpc::Status(CodeFor(kind), message);
}

grpc::Status ToStatus(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const cache::DatabaseError& e) {
    return grpc::Status(grpc::StatusCode::INTERNAL, std::string("database: ") + e.what());
  } catch (...) {
    const ClassifiedError e = ClassifyCurrentException();
    return StatusFor(e.kind, e.message);
  }
}

}  // namespace gonogo::server
