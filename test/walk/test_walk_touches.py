"""Unplanned touches (`gait_planner.walk.touches`): a point loaded where the plan holds it at
neither neighbouring node is a touch; one the plan strikes soon after is an early strike,
any other a scuff; a walk reports its touches, and its rerun view marks them."""

from __future__ import annotations

import numpy as np
import pytest

from gait_planner.walk.touches import EARLY, Touches

TIMES = np.arange(0.0, 0.65, 0.05)  # nodes 0.00 .. 0.60 s
# the heel is held at nodes 0-1 and again from node 8 (0.40 s); the toe at every node
ACTIVE = [("heel", "toe")] * 2 + [("toe",)] * 6 + [("heel", "toe")] * 5


def _touches(loads: dict[float, float]) -> list[dict]:
    touches = Touches(TIMES, ACTIVE, ["heel", "toe"], threshold=50.0)
    for t in np.arange(0.0, 0.6, 0.005):
        heel = next((f for (start, f) in loads.items() if start <= t < start + 0.02), 0.0)
        touches.update(float(t), np.array([heel, 500.0]))
    return touches.summary()


def test_held_points_and_light_loads_are_no_touch():
    assert _touches({0.0: 400.0}) == []  # held at nodes 0-1
    assert _touches({0.2: 40.0}) == []  # below the threshold


def test_a_load_just_before_the_strike_is_an_early_strike():
    (touch,) = _touches({0.33: 900.0})  # the plan strikes at 0.40 s; the node after 0.35 holds it
    assert touch["kind"] == "early strike" and touch["point"] == "heel"
    assert touch["early_s"] == pytest.approx(0.40 - 0.33, abs=1e-9) and touch["early_s"] <= EARLY
    assert touch["peak_n"] == 900.0 and 0.33 <= touch["start_s"] < touch["end_s"] < 0.35


def test_a_load_in_mid_swing_is_a_scuff():
    (touch,) = _touches({0.15: 700.0})
    assert touch["kind"] == "scuff" and "early_s" not in touch


def test_a_chattering_point_is_one_touch_and_a_later_load_another():
    touches = Touches(TIMES, ACTIVE, ["heel", "toe"], threshold=50.0)
    for k, t in enumerate(np.arange(0.10, 0.23, 0.001)):  # mid-swing: loaded every other ms
        touches.update(float(t), np.array([600.0 if k % 2 == 0 and t < 0.2 else 0.0, 500.0]))
    touches.update(0.25, np.array([300.0, 500.0]))  # 50 ms after the chatter ended
    first, second = touches.summary()
    assert first["start_s"] == pytest.approx(0.10) and first["end_s"] == pytest.approx(0.198)
    assert second["start_s"] == 0.25 and second["kind"] == "scuff"


@pytest.mark.slow
def test_a_walk_reports_its_touches(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    from gait_planner.walk.walk_plan import load_config, walk

    out = tmp_path / "w3.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", "walker3d", "--out", str(out), "--no-rrd"],
                   check=True, capture_output=True)
    config = load_config()
    config["placement"]["swing_margin"] = 0.0
    summary = walk(out, 2, config=config, series=True)
    # aimed at the plan's own swing height, the default plan's first heel strike comes
    # 15-25 ms early in MuJoCo (2026-11-29; none with config/walk.yaml's 1 cm margin)
    first = summary["unplanned_touches"][0]
    assert first["kind"] == "early strike" and first["point"].endswith("heel")
    assert 0.0 < first["early_s"] < 0.05
    # the walk's rerun view marks it where the simulated heel was, while it lasts
    from rerun.chunk import RrdReader

    from gait_planner.viz.rerun_walk import save_walk_rrd

    rrd = save_walk_rrd(summary, tmp_path / "walk.rrd")
    paths = {chunk.entity_path for chunk in RrdReader(rrd).stream()}
    assert f"/world/sim/touches/{first['point']}" in paths
