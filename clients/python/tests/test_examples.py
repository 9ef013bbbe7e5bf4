"""The examples in examples/python run against a real simulation service and print their
result line (evaluate_served.py is checked against pnpctl in test_platform.py)."""

import os
import re
import subprocess
import sys

from conftest import SOURCE_DIR


def run_example(name, *args):
    return subprocess.run([sys.executable, str(SOURCE_DIR / "examples" / "python" / name), *args],
                          env=dict(os.environ), capture_output=True, text=True, timeout=300,
                          check=True).stdout


def test_the_random_agent_reports_its_success(sim_server):
    out = run_example("random_agent.py", "--sim", sim_server.address, "--episodes", "3")
    assert re.match(r"random agent, gym/fetch/block: success 0\.\d{3} over 3 episodes "
                    r"\(seed 0\), mean final distance 0\.\d{3} m", out), out


def test_hindsight_relabelling_turns_failures_into_reached_goals(sim_server):
    out = run_example("her_relabel.py", "--sim", sim_server.address, "--episodes", "4",
                      "--batch", "512")
    m = re.search(r"(\d\.\d{3}) of stored transitions reach their goal; .*: (\d\.\d{3})", out)
    assert m, out
    assert float(m.group(2)) > float(m.group(1))


def test_an_example_refuses_a_bad_argument_by_name(sim_server):
    result = subprocess.run(
        [sys.executable, str(SOURCE_DIR / "examples" / "python" / "random_agent.py"), "--sim",
         sim_server.address, "--episodes", "0"], capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert "--episodes: expected a positive integer, got 0" in result.stderr
