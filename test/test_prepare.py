"""`pipeline.prepare` (the node's prepare_on_start) leaves a first request nothing to load:
the problem is built and the modules that certify and record a plan are imported (in a
fresh process, as this test process has imported them already). The node's prepare
(rrd=False) leaves rerun to its .rrd helper process."""

from __future__ import annotations

import subprocess
import sys

import pytest

CHILD = """
import sys
from gait_planner.ocp.solve import Planner
from gait_planner.pipeline import prepare
from gait_planner.problem import resolve
from gait_planner.request import PlanRequest
recording = ["gait_planner.io.mcap_writer", "gait_planner.viz.rerun_view", "pinocchio",
             "gait_planner.verify.continuous", "gait_planner.io.messages"]
before = [m for m in recording if m in sys.modules]
planner = Planner()
prepare(planner, resolve(PlanRequest(scene="compass", compiled=False)), rrd={rrd})
print(before, [m for m in recording if m not in sys.modules], len(planner._built))
"""


@pytest.mark.parametrize("rrd, left", [(True, []), (False, ["gait_planner.viz.rerun_view"])])
def test_prepare_builds_the_problem_and_loads_the_recording_path(rrd, left):
    out = subprocess.run([sys.executable, "-c", CHILD.format(rrd=rrd)], capture_output=True,
                         text=True, check=True, timeout=300)
    assert out.stdout.strip().splitlines()[-1] == f"[] {left} 1"
