"""Errors the package raises: a service's refusal carries its gRPC status and message."""

from __future__ import annotations

import grpc


class PlatformError(Exception):
    """A call to a platform service failed.

    `code` is the gRPC status code (grpc.StatusCode), `details` the server's message (which
    names the field and the value it expected), `method` the RPC and `address` the service.
    """

    def __init__(self, method: str, address: str, code: grpc.StatusCode, details: str):
        self.method = method
        self.address = address
        self.code = code
        self.details = details
        super().__init__(f"{method} at {address}: {code.name}: {details}")


def from_rpc_error(error: grpc.RpcError, method: str, address: str,
                   endpoints=None) -> PlatformError:
    """The PlatformError for a failed call (grpc.RpcError carries code() and details()); an
    UNAVAILABLE one names the endpoints file its address came from, if any."""
    code = error.code() if hasattr(error, "code") else grpc.StatusCode.UNKNOWN
    details = (error.details() if hasattr(error, "details") else str(error)) or ""
    if code == grpc.StatusCode.UNAVAILABLE and "Socket closed" in details:
        details += (" (the server closed the connection at once: if it serves TLS, give "
                    "tls_ca, or PNP_TLS_CA)")
    if code == grpc.StatusCode.UNAVAILABLE and endpoints is not None:
        details += endpoints.unavailable_hint()
    return PlatformError(method, address, code, details)


class ReplyError(RuntimeError):
    """A reply whose shape is not the protocol's (a count or a vector's size): a server of
    another version, or one that misbehaves. Raised before anything is built from it."""
