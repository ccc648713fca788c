"""Unitree G1 (example-robot-data) planned from its own URDF and walked on it (issue #37
item 5): `walk(..., robot=RobotUrdf(...))`, its own inertias, its four 5 mm foot spheres.

The draft keeps the URDF's joint ranges (hip yaw +-89.5 deg): minimal kinetic energy then
swings the hips' yaw by 80 deg and the walk falls in the second half cycle. Planned with
walker3d's walking ranges (hip pitch [-45, 25], roll and yaw +-15, knee [0, 75], ankle
pitch [-30, 30] and roll +-15 deg, torso within 5 deg of vertical), measured 2026-11-30
(evening) with config/walk.yaml: 5 of 10 half cycles, then the torso tilts past 35 deg
(2 of 10 on 2026-11-29, before the swing foot aimed 1 cm above the plan mid-swing: the
torso rolled and yawed away from the plan, the stance foot rocking heel-toe on its
spheres). Gains (joints, torso, placement, scaled by m g L) gave 2-3 half cycles; a stiffer
contact (0.0025 s at a 0.25 ms step) once gave 9, its neighbours 2-3: the gait is on the
edge.

Asserted: the first half cycle is walked, tracking the plan within JOINT_RMS; the target
(10 half cycles, feedback at most 40 %) is an expected failure until it is met.

Slow: 81 s with the compile cache warm (~6 min the first time: compiling, then refining
40 -> 80 intervals).
"""

from __future__ import annotations

import pytest
import yaml

from gait_planner.model.loader import find_scene
from gait_planner.model.urdf_import import draft_scene
from gait_planner.ocp.solve import Planner
from gait_planner.pipeline import plan_and_record
from gait_planner.request import PlanRequest

mujoco = pytest.importorskip("mujoco")

from gait_planner.walk.robot_urdf import RobotUrdf  # noqa: E402
from gait_planner.walk.walk_plan import walk  # noqa: E402
from gait_planner.problem import resolve

pytestmark = pytest.mark.slow

JOINT_RMS = 2.0  # deg, first half cycle (measured 0.5-0.8)
WALKING = {"hip_pitch": [-45, 25], "hip_roll": [-15, 15], "hip_yaw": [-15, 15],
           "knee": [0, 75], "ankle_pitch": [-30, 30], "ankle_roll": [-15, 15]}


@pytest.fixture(scope="module")
def g1_walk(example_robots, tmp_path_factory):
    """The summary of G1's plan (walking ranges) walked 10 half cycles on its own URDF."""
    folder = tmp_path_factory.mktemp("g1")
    urdf = example_robots / "g1_description/urdf/g1_29dof_rev_1_0.urdf"
    text = urdf.read_text()
    dirs = (str(example_robots.parents[1]),)
    draft = draft_scene(text, package_dirs=dirs, urdf_file=str(urdf))
    scene = yaml.safe_load(draft.yaml)
    options = scene["gait"]["options"]
    options["torso_lean_max"] = 5
    options["joint_limits"] = {f"{side}_{name}_joint": limits for side in ("left", "right")
                               for name, limits in WALKING.items()}
    path = folder / "g1.yaml"
    path.write_text(yaml.safe_dump(scene, sort_keys=False))
    problem = resolve(PlanRequest(scene=str(path), output_name="g1", compiled=True),
                      find_scene)
    outcome = plan_and_record(Planner(), problem, folder, rrd=False)
    assert outcome.result.success, outcome.result.message
    return walk(outcome.mcap_path, 10, robot=RobotUrdf(text, dirs, draft.locked))


def test_g1_walks_its_first_half_cycle_on_its_own_urdf(g1_walk):
    assert g1_walk["half_cycles_walked"] >= 1, g1_walk["stopped"]
    assert g1_walk["joint_rms_per_half_cycle_deg"][0] < JOINT_RMS


@pytest.mark.xfail(strict=True, reason="measured 2026-11-30: 5 of 10 half cycles, then the "
                   "torso tilts past 35 deg (issue #40 open)")
def test_g1_walks_ten_half_cycles_with_feedback_at_most_40_percent(g1_walk):
    assert g1_walk["half_cycles_walked"] == 10, g1_walk["stopped"]
    assert g1_walk["feedback_share"] <= 0.40
