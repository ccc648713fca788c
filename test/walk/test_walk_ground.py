"""A plan for a ramp or stairs walked in MuJoCo on that ground (`walk.mujoco_model` builds
the turned plane or the treads; `walk.reference` joins half cycles one rise higher).

Measured 2026-11-27 with config/walk.yaml: walker2d 10 deg down walks 4 of 10 half cycles,
its first with 0.46 deg joint RMS (as the level plan's); 0.15 m stairs up 3 of 10. The
level-ground controller then drifts; the first half cycle is what these tests hold: were
the ground in MuJoCo not the plan's (a level plane under a ramp plan, treads a step off),
the walker would leave the plan at once. The walk's ground forces are read on either
ground (the treads are no plane named "ground").
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("mujoco")


def _plan(folder: Path, *options: str, scene: str = "walker2d") -> Path:
    out = folder / "plan.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", scene, *options, "--out", str(out),
                    "--no-rrd"], check=True, capture_output=True)
    return out


# walker2d's cold stairs up at 0.15 m is a coin flip on round-off; 0.155 m converges
# (test/ocp/test_ocp_ground.py: STAIR_UP)
@pytest.mark.slow
@pytest.mark.parametrize("options", [("--slope", "-10"), ("--step-height", "0.155")])
def test_the_first_half_cycle_on_the_planned_ground_follows_the_plan(tmp_path, options):
    from gait_planner.walk.walk_plan import walk

    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.walk.reference import scene_of

    path = _plan(tmp_path, *options)
    summary = walk(path, 2, series=True)
    assert summary["half_cycles_walked"] >= 1, summary["stopped"]
    assert summary["joint_rms_per_half_cycle_deg"][0] < 1.5
    # the ground (a turned plane or the treads) carries the walker: over its first half
    # cycle the mean vertical force is its weight, as periodic motion has it
    series = summary["series"]
    first = series["time"] < read_plan_mcap(path).times[-2]
    weight = 9.81 * sum(b.mass for b in scene_of(read_plan_mcap(path)).bodies)
    lift = series["ground_force"][first][:, :, 2].sum(axis=1).mean()
    assert lift == pytest.approx(weight, rel=0.1)


# walker3d on 10 deg ramps with config/walk.yaml (2026-11-30, benchmarks/walk.py): down walks
# 10 of 10 (feedback 34 %), up 10 (35 %). Up walked 3 before the torso's position was carried
# by the legs on the ground and MuJoCo's no-slip solver stopped the stance foot's creep: the
# walker fell 4-9 cm further behind its plan every half cycle (issue #40 item 1)
@pytest.mark.slow
@pytest.mark.parametrize("slope", ["-10", "10"])
def test_walker3d_walks_a_ramp_plan_ten_half_cycles(tmp_path, slope):
    from gait_planner.walk.walk_plan import walk

    summary = walk(_plan(tmp_path, "--slope", slope, scene="walker3d"), 10)
    assert summary["half_cycles_walked"] == 10, summary["stopped"]
    assert summary["feedback_share"] <= 0.40


# walker3d's stairs planned as `gait-planner plan` and the node plan them (from the warm-start
# store's anchors) and walked with config/walk.yaml (2026-11-30, benchmarks/HISTORY.md): down
# 0.10 m walks 10 of 10 (feedback 44.5 %; 41-45 % under five controller changes tried), its
# x0 self-test 2 and x0.5 3; up 0.05 m 10 (39 %), up 0.10 m 3, up 0.15 m 5, down 0.15 m 6.
# Issue #40 asks +-0.15 m at <= 40 %: not met; this holds the stairs plan that walks.
@pytest.mark.slow
def test_walker3d_walks_a_stairs_down_plan_ten_half_cycles_and_not_without_its_torques(
        tmp_path):
    from gait_planner.cli.walk import self_test
    from gait_planner.walk.walk_plan import walk

    plan = _plan(tmp_path, "--step-height", "-0.10", scene="walker3d")
    full = walk(plan, 10)
    assert full["half_cycles_walked"] == 10, full["stopped"]
    assert full["feedback_share"] <= 0.5
    zero = next(r for r in self_test(str(plan), 10, full) if r["torque_scale"] == 0)
    assert zero["half_cycles_walked"] < 10
