"""A robot's own URDF planned (issue #37): Bolt from the example-robot-data wheel, drafted
(`gait_planner.model.urdf_import`), planned, recorded and read back as a user would.

* the plan converges and passes every check of the verifier, the continuous-dynamics
  certificate included;
* the recorded JointTrajectory names the URDF's joints, and its torques stay within the
  URDF's effort limits;
* Pinocchio's forward kinematics of the published joint angles on the original URDF (its
  base placed as the recorded root body) puts every held contact point where the plan
  publishes it (1e-6 m).

Slow: Bolt's problem builds in ~15 s and solves in ~10 s (refined once) without compiling.
"""

from __future__ import annotations


import numpy as np
import pinocchio as pin
import pytest
import yaml

from gait_planner.cli.robot import write_draft
from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.model.angles import configuration
from gait_planner.model.loader import find_scene
from gait_planner.model.urdf_import import draft_scene
from gait_planner.ocp.solve import Planner
from gait_planner.pipeline import plan_and_record
from gait_planner.request import PlanRequest
from gait_planner.verify import verify_recording


pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def bolt(example_robots, tmp_path_factory):
    """(URDF text, draft, Outcome) of Bolt planned and recorded once for the module."""
    folder = tmp_path_factory.mktemp("bolt")
    path = example_robots / "bolt_description/robots/bolt.urdf"
    urdf = path.read_text()
    draft = draft_scene(urdf, package_dirs=[str(example_robots.parents[1])],
                        urdf_file=str(path))
    scene_file = write_draft(draft, folder / "bolt.yaml")
    outcome = plan_and_record(Planner(), PlanRequest(scene=str(scene_file), output_name="bolt",
                                                     compiled=False),
                              folder, rrd=False, scenes=find_scene)
    return urdf, draft, outcome


@pytest.mark.xfail(strict=True, reason="measured 2026-11-28: every check passes but one, "
                   "the verifier counts the swing point foot at node 0 (where it lifts off, "
                   "the compass phases' release) as scuffing; issue #37 stays open")
def test_bolt_plans_and_passes_every_check(bolt):
    _, _, outcome = bolt
    assert outcome.result.success, outcome.result.message
    report = verify_recording(outcome.mcap_path)
    assert report.ok, report.failures


def test_bolt_trajectory_is_in_the_urdfs_joints_and_limits(bolt):
    urdf, draft, outcome = bolt
    rec = read_plan_mcap(outcome.mcap_path)
    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    assert set(draft.joints) <= set(rec.joint_names)
    assert all(model.existJointName(n) for n in draft.joints)
    limits = yaml.safe_load(draft.yaml)["gait"]["options"]["effort_limits"]
    effort = np.asarray(rec.effort)
    for i, name in enumerate(rec.joint_names):
        if name in limits:
            assert np.abs(effort[:, i]).max() <= limits[name] * (1 + 1e-6), name


def test_published_angles_put_the_held_contacts_where_the_plan_has_them(bolt):
    urdf, _, outcome = bolt
    rec = read_plan_mcap(outcome.mcap_path)
    scene = outcome.result.scene
    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    data = model.createData()
    root = scene.body_index(scene.root.body)
    com_link = model.inertias[1].lever  # the base's COM in its link frame (merged links)
    q0 = configuration(scene)  # the draft's pose: the URDF's zero, the base link at identity
    R_root = _directors(q0, root)  # the root's principal axes in its link frame

    def pin_q(q_row, angles):
        rotation = _directors(q_row, root) @ R_root.T
        q = pin.neutral(model)
        q[:3] = q_row[12 * root:12 * root + 3] - rotation @ com_link
        q[3:7] = pin.Quaternion(rotation).coeffs()
        for name, angle in angles.items():
            q[model.joints[model.getJointId(name)].idx_q] = angle
        return q

    feet = {c.body for c in scene.contacts}
    foot_joint = {b: next(j.name for j in scene.joints if j.child == b) for b in feet}
    pin.forwardKinematics(model, data, pin_q(q0, {}))
    # each contact point in its foot joint's frame, at the zero pose (constant)
    local = {}
    for c in scene.contacts:
        M = data.oMi[model.getJointId(foot_joint[c.body])]
        s = scene.body_index(c.body)
        world = q0[12 * s:12 * s + 3] + _directors(q0, s) @ np.asarray(
            scene.body(c.body).points[c.point])
        local[c.name] = M.actInv(world)
    positions = np.asarray(rec.positions)
    worst, held = 0.0, 0
    for n in range(len(rec.times)):
        angles = {name: positions[n, i] for i, name in enumerate(rec.joint_names)}
        pin.forwardKinematics(model, data, pin_q(np.asarray(rec.q[n]), angles))
        names = list(rec.contact_names[n])
        for name in rec.active_contacts[n]:
            M = data.oMi[model.getJointId(foot_joint[scene.contact(name).body])]
            planned = np.asarray(rec.contact_points[n])[names.index(name)]
            worst = max(worst, float(np.abs(M.act(local[name]) - planned).max()))
            held += 1
    assert held > 0 and worst < 1e-6


def _directors(q_row, index: int) -> np.ndarray:
    return np.asarray(q_row)[12 * index + 3:12 * index + 12].reshape(3, 3).T
