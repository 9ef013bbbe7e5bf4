"""Finds grpcio, protobuf and numpy.

The platform uses Debian's python3-grpcio, python3-protobuf and python3-numpy. They live in
Debian's dist-packages, which only Debian's own /usr/bin/python3 searches. Another CPython
of the same version (a pyenv or a venv without those packages) can load them too, since
their compiled modules are built for that version's ABI: this adds that directory, after
the interpreter's own, when a dependency is missing and the ABI matches.
"""

from __future__ import annotations

import glob
import importlib.util
import os
import sys

_DEBIAN_DIST_PACKAGES = "/usr/lib/python3/dist-packages"
_REQUIRED = ("grpc", "google.protobuf", "numpy")


def _missing() -> list[str]:
    missing = []
    for name in _REQUIRED:
        try:
            if importlib.util.find_spec(name) is None:
                missing.append(name)
        except ModuleNotFoundError:  # the parent package ("google") is missing
            missing.append(name)
    return missing


def _debian_matches_this_interpreter() -> bool:
    tag = f"cpython-{sys.version_info.major}{sys.version_info.minor}-"
    pattern = os.path.join(_DEBIAN_DIST_PACKAGES, "grpc", "_cython", f"cygrpc.{tag}*.so")
    return bool(glob.glob(pattern))


def ensure() -> None:
    """Makes the dependencies importable, or raises ImportError saying how to install them."""
    if not _missing():
        return
    if _DEBIAN_DIST_PACKAGES not in sys.path and _debian_matches_this_interpreter():
        sys.path.append(_DEBIAN_DIST_PACKAGES)
        importlib.invalidate_caches()
    missing = _missing()
    if missing:
        raise ImportError(
            f"pnp needs {', '.join(missing)}: install Debian's python3-grpcio, python3-protobuf "
            "and python3-numpy (scripts/install-deps does) and use /usr/bin/python3, or a "
            "Python with grpcio, protobuf and numpy installed")
