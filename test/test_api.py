"""The Python API (`gait_planner.api`, re-exported by the package) and its example
(examples/plan_a_gait.py), run as a user runs them."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import gait_planner
from gait_planner import PlanRequest, RequestError, check, plan, record, summary
from gait_planner.io.mcap_reader import read_plan_mcap

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plan_a_gait.py"


def test_the_package_exports_the_api_lazily():
    """`import gait_planner` alone does not load the planner (the node's workers and the
    .rrd helper import submodules only); the API names come on first use."""
    done = subprocess.run([sys.executable, "-c",
                           "import sys, gait_planner, gait_planner.model.scene; "
                           "print('gait_planner.api' in sys.modules, "
                           "'gait_planner.ocp.solve' in sys.modules)"],
                          capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", "False"]
    assert sorted(gait_planner.__all__) == sorted(gait_planner.api.__all__)
    with pytest.raises(AttributeError, match="no attribute 'plann'"):
        gait_planner.plann  # noqa: B018


def test_plan_check_record_summary(tmp_path):
    """A scene's name plans its default request; the plan passes the verifier, its
    recording reads back with the plan's nodes, its summary says what was planned."""
    result = plan("compass")
    assert result.success, result.message
    assert check(result).ok
    mcap = record(result, tmp_path / "new" / "compass.mcap", rrd=True)
    assert mcap.with_suffix(".rrd").is_file()
    assert read_plan_mcap(mcap).q.shape[0] == result.n_nodes
    data = summary(result)
    assert data["scene"] == "compass" and data["success"] and data["mcap"] == ""


def test_a_request_the_scene_cannot_plan_is_refused_with_its_reason():
    with pytest.raises(RequestError, match="friction_coefficient"):
        plan(PlanRequest("compass", friction_coefficient=-1.0))
    with pytest.raises(RequestError, match="no_such_scene"):
        plan("no_such_scene")


def test_the_example_plans_checks_and_records(tmp_path):
    done = subprocess.run([sys.executable, str(EXAMPLE), str(tmp_path)], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "verdict: all checks passed" in done.stdout
    recording = read_plan_mcap(tmp_path / "ramp.mcap")
    assert (recording.metadata["scene"], recording.metadata["slope"]) == ("walker3d", "5.0")
    assert len(EXAMPLE.read_text().splitlines()) <= 40
