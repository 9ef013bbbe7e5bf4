"""The Python client against servers that require TLS and an authorized principal
(scripts/make-dev-certs): readers read, only an operator promotes, plaintext is refused."""

import subprocess

import grpc
import pytest

import pnp
from conftest import SOURCE_DIR, Server


@pytest.fixture(scope="module")
def secured(tmp_path_factory, store_with_hierarchy):
    workdir = tmp_path_factory.mktemp("secured")
    certs = workdir / "certs"
    subprocess.run([str(SOURCE_DIR / "scripts" / "make-dev-certs"), "--out", str(certs)],
                   check=True, capture_output=True)
    server = Server("inference_tls", [
        "pnp-inference-server", "--db", str(store_with_hierarchy),
        "--tls-cert", str(certs / "server.pem"), "--tls-key", str(certs / "server.key"),
        "--auth-policy", str(certs / "policy.json")], workdir)
    yield server, certs
    server.stop()


def platform_as(secured, who):
    server, certs = secured
    return pnp.Platform(pnp.Endpoints(inference=server.address, tls_ca=str(certs / "ca.pem"),
                                      token_file=str(certs / f"{who}.token")))


def test_a_reader_reads_but_may_not_promote(secured):
    with platform_as(secured, "reader") as platform:
        status = platform.serving_status()
        assert status["ready"]
        ids = [r["checkpoint_id"] for r in status["roles"]]
        with pytest.raises(pnp.PlatformError) as e:
            platform.promote(*ids)
    assert e.value.code == grpc.StatusCode.PERMISSION_DENIED
    token = (secured[1] / "reader.token").read_text().strip()
    assert token not in str(e.value)  # a secret is never echoed back


def test_an_operator_promotes(secured):
    with platform_as(secured, "ops") as platform:
        ids = sorted(r["checkpoint_id"] for r in platform.serving_status()["roles"])
        promoted = platform.promote(*ids)
    assert sorted(p["checkpoint_id"] for p in promoted) == ids


def test_plaintext_is_refused(secured):
    server, _ = secured
    with pnp.Platform(pnp.Endpoints(inference=server.address), timeout_s=5) as platform:
        with pytest.raises(pnp.PlatformError) as e:
            platform.serving_status()
    assert e.value.code == grpc.StatusCode.UNAVAILABLE
