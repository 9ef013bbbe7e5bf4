"""Where each platform service listens and how to reach it (plaintext, TLS, mutual TLS,
with or without a bearer token): the same settings, environment variables and defaults as
pnpctl (`pnpctl --help`)."""

from __future__ import annotations

import dataclasses
import json
import os
from typing import Mapping

import grpc

# The services of a platform, by the name pnpctl gives them, and their conventional ports.
SERVICES = ("sim", "approach", "manipulate", "retract", "hlc", "e2e", "inference")
TRAINING_ROLES = ("approach", "manipulate", "retract", "hlc", "e2e")
_MAX_MESSAGE_BYTES = 64 << 20  # as pnpctl: a run's metrics or a checkpoint list can be large
# How inference replicas are reached (round_robin over every address the target resolves
# to, idempotent calls retried on UNAVAILABLE): the JSON the C++ clients embed, from
# proto/pnp/policy/v1/, shipped beside this module.
_REPLICA_SERVICE_CONFIG = "replica_service_config.json"


def replica_service_config() -> str:
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), _REPLICA_SERVICE_CONFIG)
    with open(path, encoding="utf-8") as f:
        return f.read()


@dataclasses.dataclass(frozen=True)
class Endpoints:
    sim: str = "127.0.0.1:50051"
    approach: str = "127.0.0.1:50052"
    manipulate: str = "127.0.0.1:50053"
    retract: str = "127.0.0.1:50054"
    hlc: str = "127.0.0.1:50055"
    e2e: str = "127.0.0.1:50056"
    inference: str = "127.0.0.1:50060"
    # PEM files; tls_ca set: dial TLS. tls_cert and tls_key: mutual TLS. token_file: its
    # first line is sent as "authorization: Bearer ..." (TLS only, as pnpctl).
    tls_ca: str | None = None
    tls_cert: str | None = None
    tls_key: str | None = None
    tls_server_name: str | None = None
    token_file: str | None = None
    # The endpoints file the addresses came from (discover()), named when a service there
    # does not answer: the platform that wrote it may have stopped.
    source: str | None = None

    @classmethod
    def from_mapping(cls, values: Mapping[str, str],
                     base: "Endpoints | None" = None) -> "Endpoints":
        """`base` (default: the conventional loopback ports) with the given fields replaced;
        an unknown name raises ValueError naming it."""
        known = {f.name for f in dataclasses.fields(cls)} - {"source"}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(f"endpoints: unknown service or setting {unknown[0]!r}; expected one "
                             f"of {', '.join(sorted(known))}")
        return dataclasses.replace(base or cls(), **dict(values))

    @classmethod
    def from_file(cls, path: str, base: "Endpoints | None" = None) -> "Endpoints":
        """A JSON object of addresses such as scripts/run writes to runs/platform/endpoints.json."""
        with open(path, encoding="utf-8") as f:
            values = json.load(f)
        if not isinstance(values, dict):
            raise ValueError(f"{path}: expected a JSON object of service addresses")
        try:
            return dataclasses.replace(cls.from_mapping(values, base), source=path)
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from None

    @classmethod
    def from_env(cls, base: "Endpoints | None" = None) -> "Endpoints":
        """`base` with pnpctl's environment variables applied (PNP_SIM_ADDRESS, ...,
        PNP_TLS_CA, PNP_TLS_CERT, PNP_TLS_KEY, PNP_TOKEN_FILE)."""
        values = {}
        for name in SERVICES:
            address = os.environ.get(f"PNP_{name.upper()}_ADDRESS")
            if address:
                values[name] = address
        for name in ("tls_ca", "tls_cert", "tls_key", "token_file"):
            value = os.environ.get(f"PNP_{name.upper()}")
            if value:
                values[name] = value
        return cls.from_mapping(values, base)

    @classmethod
    def discover(cls, run_dir: str = "runs/platform") -> "Endpoints":
        """Where pnpctl would look: pnpctl's environment variables (PNP_SIM_ADDRESS, ...),
        then the endpoints file PNP_ENDPOINTS names (it must exist), else RUN_DIR/endpoints.json
        (scripts/run writes it while the platform runs) when it exists, then the conventional
        ports."""
        path = os.environ.get("PNP_ENDPOINTS") or os.path.join(run_dir, "endpoints.json")
        if os.environ.get("PNP_ENDPOINTS") and not os.path.exists(path):
            raise ValueError(f"PNP_ENDPOINTS: cannot read {path}")
        base = cls.from_file(path) if os.path.exists(path) else None
        return cls.from_env(base)

    def unavailable_hint(self) -> str:
        """What to say when a service does not answer: where its address came from."""
        if not self.source:
            return ""
        return (f" (the addresses came from {self.source}: if the platform that wrote it has "
                f"stopped, start it again with scripts/run, or set PNP_*_ADDRESS)")

    def training(self, role: str) -> str:
        if role not in TRAINING_ROLES:
            raise ValueError(f"role: expected one of {', '.join(TRAINING_ROLES)}, got {role!r}")
        return getattr(self, role)

    def channel(self, address: str) -> grpc.Channel:
        """A channel to `address` with these credentials. Inference replicas are
        interchangeable: its channel balances over all of them (`dns:///name:port` or
        `ipv4:a:p,b:p`), retrying the idempotent calls on another one; a session stays on
        the replica it began on."""
        options = [("grpc.max_receive_message_length", _MAX_MESSAGE_BYTES)]
        if address == self.inference:
            options += [("grpc.service_config", replica_service_config()),
                        ("grpc.enable_retries", 1)]
        if not self.tls_ca:
            if self.tls_cert or self.tls_key or self.token_file:
                raise ValueError("tls_ca: expected a CA file when tls_cert, tls_key or "
                                 "token_file is set (a token is never sent in plaintext)")
            return grpc.insecure_channel(address, options=options)
        if bool(self.tls_cert) != bool(self.tls_key):
            raise ValueError("tls_cert and tls_key: expected both (mutual TLS) or neither")
        credentials = grpc.ssl_channel_credentials(
            root_certificates=_read(self.tls_ca, "tls_ca"),
            private_key=_read(self.tls_key, "tls_key") if self.tls_key else None,
            certificate_chain=_read(self.tls_cert, "tls_cert") if self.tls_cert else None)
        if self.token_file:
            token = _read(self.token_file, "token_file").decode().splitlines()
            if not token or not token[0].strip():
                raise ValueError(f"token_file: expected a token on the first line of "
                                 f"{self.token_file}")
            credentials = grpc.composite_channel_credentials(
                credentials, grpc.access_token_call_credentials(token[0].strip()))
        if self.tls_server_name:
            options.append(("grpc.ssl_target_name_override", self.tls_server_name))
        return grpc.secure_channel(address, credentials, options=options)


def _read(path: str, field: str) -> bytes:
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as e:
        raise ValueError(f"{field}: cannot read {path}: {e.strerror}") from e
