"""Robots the importer once refused as asymmetric plan (issue #61 item 4). iCub from the
example-robot-data wheel, whose base x points backwards, whose right leg link frames are
not its left leg's mirrored and whose right leg links have a mass but no inertia in the
URDF, drafted (`gait_planner.model.urdf_import`), planned and recorded as a user plans it:

* the draft walks along the base's -x (its header says the soles told it), its walking
  frame snapped onto the URDF's axes;
* the plan converges and passes every check of the verifier, the continuous-dynamics
  certificate on the original URDF included (the right leg's missing inertias certified
  with the draft's, `gait_planner.verify.robot`);
* its legs' collision geometry, measured by coal at every node, is at least the draft's
  leg_clearance apart, each held foot stays on its own side of the mid-plane, and every
  published effort (its locked wrists' 0.45-0.65 N m included) is within the URDF's limit;
* the plan walks forward: its root moves along the walker's +x, which is the URDF base's
  -x, by a step (to 5 %).

Until its Collada meshes were turned to z up (`gait_planner.model.urdf_contacts.turn_y_up`)
its shanks lay across its hips: the spheres the leg rows keep apart overlapped by 29 cm
standing and its plan did not converge (400 s, 1342 iterations; benchmarks/HISTORY.md).

Alexander (lower body): its links named LEFT_/RIGHT_, its left and right link frames not
mirrored, its feet with visual meshes only; at a 0.45 m step the cold plan converges and
passes every check (its drafted 0.6688 m does not converge in 600 s, nor did 0.6 m in a
first run of this test).

Romeo (`romeo_small.urdf`): its joints' own URDF velocity limits (hip yaw 18.3 deg/s, hip
and ankle 120, knee 344; `joint_speed_limits`), not its slowest for every joint; its draft
as drafted, whose sigma bound its slow hip and ankle pitch joints raise from 1.5 to 3.0
(`gait_planner.model.urdf_pace`: a half cycle of up to 1.04 s; at 1.5 no plan converged in
600 s, the joint speed rows most violated), plans cold and passes every check, its ankles
and hip yaws at their own limits, no joint above its own.

Slow: without compiling, iCub's problem builds and solves in about 2 min (6 GB of memory:
run it alone), Alexander's in about 1 min, Romeo's in about 2 min (5.2 GB).
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from gait_planner.cli.robot import write_draft
from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.model.loader import find_scene
from gait_planner.model.urdf_import import draft_scene
from gait_planner.ocp.solve import Planner
from gait_planner.pipeline import plan_and_record
from gait_planner.problem import resolve
from gait_planner.request import PlanRequest
from gait_planner.verify import verify_recording
from gait_planner.verify.effort_limits import LIMIT_TOLERANCE, effort_shares

pytestmark = pytest.mark.slow

ICUB = "icub_description/robots/icub_reduced.urdf"
ALEXANDER = "alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf"
ROMEO = "romeo_description/urdf/romeo_small.urdf"


def _planned_and_checked(scene_file, name: str, tmp_path, **request):
    """(Outcome, report) of the scene file planned cold and recorded as a user plans it,
    asserted converged and passing every check of the verifier."""
    problem = resolve(PlanRequest(scene=str(scene_file), output_name=name, compiled=False,
                                  **request), find_scene)
    outcome = plan_and_record(Planner(), problem, tmp_path, rrd=False)
    assert outcome.result.success, outcome.result.message
    report = verify_recording(outcome.mcap_path)
    assert report.ok, report.failures
    return outcome, report


def test_icub_walks_along_its_base_minus_x_and_passes_every_check(example_robots, tmp_path):
    path = example_robots / ICUB
    urdf = path.read_text()
    draft = draft_scene(urdf, package_dirs=[str(example_robots.parents[1])],
                        urdf_file=str(path))
    assert "Walking direction (the scene's x): the URDF's [-1.0, 0.0, 0.0], told by the " \
        "soles" in draft.yaml
    assert "walking frame: turned by 4.71e-05 rad" in draft.yaml  # its rpy of 1.5708
    outcome, report = _planned_and_checked(write_draft(draft, tmp_path / "icub.yaml"), "icub",
                                           tmp_path)
    clearance = yaml.safe_load(draft.yaml)["gait"]["options"]["leg_clearance"]
    assert report.legs.source == "the URDF's collision geometry (coal)"
    assert clearance == 0.01 and report.legs.smallest >= clearance, \
        (report.legs.pair, report.legs.node, report.legs.smallest)
    rec = read_plan_mcap(outcome.mcap_path)
    shares = effort_shares(urdf, rec.joint_names, np.asarray(rec.effort))
    assert set(draft.locked) <= set(shares)  # the locked wrists judged too
    worst = max(shares, key=lambda name: shares[name][0])
    assert shares[worst][0] <= 1.0 + LIMIT_TOLERANCE, (worst, shares[worst])
    side = {c.name: 1.0 if c.name.startswith("foot_l") else -1.0 for c in
            outcome.result.scene.contacts}
    across = min(side[name] * float(np.asarray(rec.contact_points[n])[i][1])
                 for n in range(len(rec.times)) for i, name in enumerate(rec.contact_names[n])
                 if name in rec.active_contacts[n])
    assert across > 0.0, f"a held foot {-across:.3f} m across the mid-plane"
    scene = outcome.result.scene
    root = scene.body_index(scene.root.body)
    q = np.asarray(rec.q)
    advance = q[-1, 12 * root] - q[0, 12 * root]
    assert advance == pytest.approx(scene.gait.step_length, rel=0.05)


def test_alexander_plans_at_a_shorter_step_and_passes_every_check(example_robots, tmp_path):
    path = example_robots / ALEXANDER
    draft = draft_scene(path.read_text(), package_dirs=[str(example_robots.parents[1])],
                        urdf_file=str(path))
    assert "RIGHT_THIGH: centre of mass moved by 0.136 mm to be LEFT_THIGH's mirror image" \
        in draft.yaml
    _planned_and_checked(write_draft(draft, tmp_path / "alexander.yaml"), "alexander",
                         tmp_path, step_length=0.45)


def test_romeo_plans_within_each_joints_own_speed_limit(example_robots, tmp_path):
    path = example_robots / ROMEO
    draft = draft_scene(path.read_text(), package_dirs=[str(example_robots.parents[1])],
                        urdf_file=str(path))
    options = yaml.safe_load(draft.yaml)["gait"]["options"]
    limits = options["joint_speed_limits"]
    assert "joint_speed_max" not in options
    assert limits["LHipYaw"] == pytest.approx(np.degrees(0.32), abs=1e-5)
    assert limits["RKneePitch"] == pytest.approx(np.degrees(6.0), abs=1e-5)
    assert yaml.safe_load(draft.yaml)["gait"]["scaling_bounds"] == [0.5, 3.0]  # its pace
    outcome, _ = _planned_and_checked(write_draft(draft, tmp_path / "romeo.yaml"), "romeo",
                                      tmp_path)
    rec = read_plan_mcap(outcome.mcap_path)
    speed = np.degrees(np.abs(np.asarray(rec.velocities))).max(axis=0)
    shares = {name: speed[rec.joint_names.index(name)] / limit
              for name, limit in limits.items()}
    assert max(shares.values()) <= 1.0 + 1e-6, shares
    assert shares["LHipYaw"] > 0.99  # the slow hip yaw rides its own 18.3 deg/s
    assert min(shares.values()) < 0.5  # the others are not held to it
