"""Builds the package with its gRPC stubs: protoc and grpc_python_plugin (Debian's
protobuf-compiler and protobuf-compiler-grpc) generate them from the repository's proto/
into the wheel, as the CMake build does into build/python. Metadata: pyproject.toml."""

import pathlib
import shutil
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py

PROTO_ROOT = pathlib.Path(__file__).resolve().parents[2] / "proto"
PROTOS = ["pnp/common/v1/common.proto", "pnp/policy/v1/policy_service.proto",
          "pnp/robot/v1/robot_controller.proto", "pnp/sim/v1/sim_service.proto",
          "pnp/train/v1/train_service.proto"]
REPLICA_SERVICE_CONFIG = "pnp/policy/v1/replica_service_config.json"


class BuildPyWithStubs(build_py):
    def run(self):
        super().run()
        protoc = shutil.which("protoc")
        plugin = shutil.which("grpc_python_plugin")
        if not protoc or not plugin:
            raise RuntimeError("protoc and grpc_python_plugin are needed to generate the stubs "
                               "(Debian: protobuf-compiler, protobuf-compiler-grpc)")
        for proto in PROTOS:
            subprocess.run([protoc, f"--proto_path={PROTO_ROOT}", f"--python_out={self.build_lib}",
                            f"--grpc_python_out={self.build_lib}",
                            f"--plugin=protoc-gen-grpc_python={plugin}", proto], check=True)
        # How inference replicas are reached, shared with the C++ clients.
        shutil.copy(PROTO_ROOT / REPLICA_SERVICE_CONFIG,
                    pathlib.Path(self.build_lib) / "pnp" / "replica_service_config.json")


setup(cmdclass={"build_py": BuildPyWithStubs})
