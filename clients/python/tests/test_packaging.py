"""`pip install ./clients/python` builds a package that works on its own: the gRPC stubs
are generated from proto/ into it, and it plays an episode with nothing from build/python."""

import os
import shutil
import subprocess
import sys

from conftest import SOURCE_DIR


def test_pip_install_gives_a_working_package(tmp_path, sim_server):
    # A copy of the package and proto/, in their places: pip builds in the tree it is given.
    source = tmp_path / "checkout"
    shutil.copytree(SOURCE_DIR / "clients" / "python", source / "clients" / "python",
                    ignore=shutil.ignore_patterns("tests", "__pycache__", "build", "*.egg-info"))
    shutil.copytree(SOURCE_DIR / "proto", source / "proto")
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-build-isolation",
                    "--no-deps", "--no-index", "--target", str(target),
                    str(source / "clients" / "python")],
                   check=True, capture_output=True, timeout=300,
                   env=dict(os.environ, PIP_NO_CACHE_DIR="1"))
    check = ("import pnp, numpy as np\n"
             "assert pnp.__file__.startswith(%r), pnp.__file__\n"
             "import json, pnp.endpoints\n"
             "assert 'round_robin' in json.loads(pnp.endpoints.replica_service_config())"
             "['loadBalancingConfig'][0]\n"
             "env = pnp.PickAndPlaceEnv(%r)\n"
             "obs, _ = env.reset()\n"
             "obs, *_ = env.step(np.zeros(4))\n"
             "print(obs['observation'].shape)\n" % (str(target), sim_server.address))
    out = subprocess.run([sys.executable, "-c", check], check=True, capture_output=True,
                         text=True, timeout=60, cwd=tmp_path,
                         env=dict(os.environ, PYTHONPATH=str(target)))
    assert out.stdout.strip() == "(25,)"
