"""The errors of the gonogo client: the server's gRPC status, with the field it names."""
import re

import grpc

# The server words a refusal "FIELD: reason" (e.g. "vehicle.mass_kg: 0 is outside [500, 100000] kg").
_FIELD = re.compile(r"^([A-Za-z_][A-Za-z0-9_.\[\]]*): ")


class GonogoError(Exception):
    """A call the server refused or could not answer.

    code:    the grpc.StatusCode (INVALID_ARGUMENT, NOT_FOUND, RESOURCE_EXHAUSTED, UNAUTHENTICATED, ...)
    field:   the request field the server named, or None
    message: the server's message
    """

    def __init__(self, code, message, field=None):
        self.code = code
        self.message = message
        self.field = field
        super().__init__(f"{code.name}: {message}")

    @classmethod
    def from_rpc_error(cls, error: grpc.RpcError) -> "GonogoError":
        message = error.details() or ""
        match = _FIELD.match(message)
        return cls(error.code(), message, match.group(1) if match else None)


class JobFailed(GonogoError):
    """A job that ended FAILED or CANCELLED; `job` is its last status."""

    def __init__(self, job_id, state, message):
        self.job_id = job_id
        self.state = state
        super().__init__(grpc.StatusCode.ABORTED, f"job {job_id} {state}: {message}")


class InputError(ValueError):
    """A local input the client cannot send (a raster it cannot read, a vehicle file that is not JSON)."""

    def __init__(self, field, reason):
        self.field = field
        super().__init__(f"{field}: {reason}")
