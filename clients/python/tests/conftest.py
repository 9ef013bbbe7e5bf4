"""Fixtures that start the platform's real servers on free loopback ports.

The build passes PNP_BIN_DIR (its bin/) and PNP_SOURCE_DIR (the checkout); each server
is started with --address 127.0.0.1:0 and prints the port it took as its first line."""

from __future__ import annotations

import os
import pathlib
import signal
import subprocess
import tempfile
import threading

import pytest

BIN_DIR = pathlib.Path(os.environ.get("PNP_BIN_DIR", "build/bin"))
SOURCE_DIR = pathlib.Path(os.environ.get("PNP_SOURCE_DIR", "."))
CHECKED_IN_HIERARCHY = SOURCE_DIR / "tests" / "data" / "panda_block"
START_TIMEOUT_S = 30


class Server:
    """A server process; its stderr goes to a file shown when a test fails to reach it."""

    def __init__(self, name: str, args: list[str], workdir: pathlib.Path):
        self.name = name
        self.log_path = workdir / f"{name}.log"
        self._log = open(self.log_path, "wb")
        self.process = subprocess.Popen([str(BIN_DIR / args[0]), *args[1:],
                                         "--address", "127.0.0.1:0"],
                                        stdout=subprocess.PIPE, stderr=self._log, cwd=workdir)
        self.port = self._read_port()
        self.address = f"127.0.0.1:{self.port}"

    def _read_port(self) -> int:
        line: list[bytes] = []
        reader = threading.Thread(target=lambda: line.append(self.process.stdout.readline()),
                                  daemon=True)
        reader.start()
        reader.join(START_TIMEOUT_S)
        if not line or not line[0].strip().isdigit():
            self.stop()
            raise RuntimeError(f"{self.name} did not start: {self.log()}")
        return int(line[0])

    def log(self) -> str:
        self._log.flush()
        return self.log_path.read_text(errors="replace")[-4000:]

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.process.stdout.close()
        self._log.close()


@pytest.fixture(scope="session")
def workdir():
    with tempfile.TemporaryDirectory(prefix="pnp_python_") as d:
        yield pathlib.Path(d)


@pytest.fixture(scope="session")
def sim_server(workdir):
    server = Server("sim", ["pnp-sim-server"], workdir)
    yield server
    server.stop()


@pytest.fixture(scope="session")
def store_with_hierarchy(workdir):
    """A store holding the checked-in Panda hierarchy, promoted (pnp-import)."""
    db = workdir / "pnp.db"
    subprocess.run([str(BIN_DIR / "pnp-import"), "--db", str(db), "--hierarchy",
                    str(CHECKED_IN_HIERARCHY), "--robot", "panda", "--object", "block"],
                   check=True, capture_output=True)
    return db


@pytest.fixture(scope="session")
def inference_server(workdir, store_with_hierarchy):
    server = Server("inference", ["pnp-inference-server", "--db", str(store_with_hierarchy)],
                    workdir)
    yield server
    server.stop()


def _training_server(role, workdir, store):
    """A training server of `role` on the shared store, one trainer thread."""
    server = Server(role, ["pnp-train-server", "--role", role, "--db", str(store),
                           "--threads", "1"], workdir)
    yield server
    server.stop()


@pytest.fixture(scope="session")
def retract_server(workdir, store_with_hierarchy):
    yield from _training_server("retract", workdir, store_with_hierarchy)


@pytest.fixture(scope="session")
def approach_server(workdir, store_with_hierarchy):
    yield from _training_server("approach", workdir, store_with_hierarchy)
