"""A robot's own URDF planned (issue #37): Bolt, Unitree G1 and Talos from the
example-robot-data wheel, drafted (`gait_planner.model.urdf_import`; Talos with
--mirror-tolerance 0.06, its leg_2 inertias being 5.35 % apart), planned, recorded and read
back as a user would.

* the plan converges and passes every check of the verifier, the continuous-dynamics
  certificate on the original URDF included;
* the recorded JointTrajectory names every joint of the URDF (the locked ones held at their
  angle), its torques stay within the URDF's effort limits, the locked joints' holding
  efforts too (issue #61; the impacts' impulses published apart), its angles within the
  draft's ranges and its rates within the joint speed bound;
* the recording's /robot_description is the URDF itself and /tf and /tf_static carry every
  one of its links; the rerun view draws the URDF's meshes, moved per node by /tf;
* Pinocchio's forward kinematics of the published joint angles on the original URDF (its
  base placed as the recorded root body) puts every held contact point where the plan
  publishes it (1e-6 m);
* each held foot stays on its own side of the walk's mid-plane (left: y > 0, right: y < 0).
  Talos's plan put each stance foot 1 to 4 cm across it until the legs were kept apart
  (`gait_planner.ocp.legs`): its legs crossed, the left ankle 14 mm into the right leg;
* the legs' collision geometry, measured by coal at every node, is at least the draft's
  leg_clearance apart.

Slow: without compiling, Bolt's problem builds and solves in about 50 s, G1's in about 4 min
(refined once to 80 intervals), Talos's in about 3 min (refined once to 80 intervals).
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
from gait_planner.verify.effort_limits import LIMIT_TOLERANCE, effort_shares
from gait_planner.problem import resolve


pytestmark = pytest.mark.slow


ROBOTS = {"bolt": ("bolt_description/robots/bolt.urdf", {}),
          "g1": ("g1_description/urdf/g1_29dof_rev_1_0.urdf", {}),
          "talos": ("talos_data/robots/talos_reduced.urdf", {"mirror_tolerance": 0.06})}


@pytest.fixture(scope="module", params=sorted(ROBOTS))
def robot(request, example_robots, tmp_path_factory):
    """(URDF text, draft, Outcome) of a robot planned and recorded once for the module."""
    name = request.param
    folder = tmp_path_factory.mktemp(name)
    relative, options = ROBOTS[name]
    path = example_robots / relative
    urdf = path.read_text()
    draft = draft_scene(urdf, package_dirs=[str(example_robots.parents[1])],
                        urdf_file=str(path), **options)
    scene_file = write_draft(draft, folder / f"{name}.yaml")
    problem = resolve(PlanRequest(scene=str(scene_file), output_name=name, compiled=False),
                      find_scene)
    outcome = plan_and_record(Planner(), problem, folder, rrd=True)
    return urdf, draft, outcome


def test_robot_plans_and_passes_every_check(robot):
    _, _, outcome = robot
    assert outcome.result.success, outcome.result.message
    report = verify_recording(outcome.mcap_path)
    assert report.ok, report.failures


def test_trajectory_is_in_the_urdfs_joints_and_limits(robot):
    urdf, draft, outcome = robot
    rec = read_plan_mcap(outcome.mcap_path)
    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    moving = [model.names[j] for j in range(2, model.njoints)]
    assert list(rec.joint_names) == list(draft.joints) + list(draft.locked)  # every joint
    assert sorted(rec.joint_names) == sorted(moving)
    options = yaml.safe_load(draft.yaml)["gait"]["options"]
    effort, position = np.asarray(rec.effort), np.asarray(rec.positions)
    speed = np.abs(np.asarray(rec.velocities)).max(axis=0)
    for i, name in enumerate(rec.joint_names):
        if name in options["effort_limits"]:
            assert np.abs(effort[:, i]).max() <= options["effort_limits"][name] * (1 + 1e-6)
        if name in options["joint_limits"]:
            low, high = np.radians(options["joint_limits"][name])
            assert low - 1e-6 <= position[:, i].min() and position[:, i].max() <= high + 1e-6
        if name in draft.locked:
            assert np.all(position[:, i] == draft.locked[name]) and speed[i] == 0.0
    own = options.get("joint_speed_limits", {})  # each joint's own limit, else one for all
    for name in draft.joints:
        limit = own.get(name, options.get("joint_speed_max"))
        if limit:  # the rows bound an interval's mean speed; the published ones are nodes'
            assert speed[rec.joint_names.index(name)] <= np.radians(limit) * 1.01, name


def test_every_published_effort_is_within_the_urdfs_limit(robot):
    """Locked joints included (issue #61): what holds them is bounded in the plan; at an
    impact node the impulse is published apart, in N m s, not folded into an effort."""
    urdf, draft, outcome = robot
    rec = read_plan_mcap(outcome.mcap_path)
    shares = effort_shares(urdf, rec.joint_names, np.asarray(rec.effort))
    assert set(draft.locked) & set(shares) or not draft.locked  # locked joints judged too
    worst = max(shares, key=lambda name: shares[name][0])
    assert shares[worst][0] <= 1.0 + LIMIT_TOLERANCE, (worst, shares[worst])
    assert set(rec.held_joint_names) == set(draft.locked)
    impacts = [n for n in range(1, len(rec.times) - 1)
               if set(rec.active_contacts[n]) - set(rec.active_contacts[n - 1])]
    struck = (np.abs(rec.held_joint_impulses) > 0).any(axis=1)
    assert impacts and set(np.flatnonzero(struck)) <= set(impacts)
    assert struck.any() or not draft.locked


def test_the_recording_is_the_robots_own(robot):
    urdf, _, outcome = robot
    rec = read_plan_mcap(outcome.mcap_path)
    assert rec.urdf == urdf
    certificate = outcome.result.settings["continuous_dynamics"]
    assert "on its URDF" in certificate and certificate.endswith("OK")
    frames = {t.child for t in rec.tf[0]} | {t.child for t in rec.tf_static}
    model = pin.buildModelFromXML(urdf)
    assert {f.name for f in model.frames if f.type == pin.FrameType.BODY} <= frames


def test_published_angles_put_the_held_contacts_where_the_plan_has_them(robot):
    urdf, _, outcome = robot
    rec = read_plan_mcap(outcome.mcap_path)
    scene = outcome.result.scene
    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    data = model.createData()
    root = scene.body_index(scene.root.body)
    q0 = configuration(scene)  # the draft's pose: the URDF's zero
    position, rotation = scene.robot.link_pose(scene.root.body)  # base link in the root body

    def pin_q(q_row, angles):
        D = _directors(q_row, root)
        q = pin.neutral(model)
        q[:3] = q_row[12 * root:12 * root + 3] + D @ position
        q[3:7] = pin.Quaternion(D @ rotation).coeffs()
        for name, angle in {**scene.robot.locked, **angles}.items():
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


def test_each_held_foot_stays_on_its_side(robot):
    _, _, outcome = robot
    rec = read_plan_mcap(outcome.mcap_path)
    side = {c.name: 1.0 if c.name.startswith("foot_l") else -1.0  # the draft's names
            for c in outcome.result.scene.contacts}
    worst = min(side[name] * float(np.asarray(rec.contact_points[n])[i][1])
                for n in range(len(rec.times))
                for i, name in enumerate(rec.contact_names[n]) if name in rec.active_contacts[n])
    assert worst > 0.0, f"a held foot {-worst:.3f} m across the mid-plane"


def test_the_legs_collision_geometry_keeps_the_clearance(robot):
    """The verifier's coal distance between the two legs' links (their URDF collision
    geometry) at every node is at least the draft's leg_clearance, which the plan kept
    between the spheres that contain them."""
    _, draft, outcome = robot
    legs = verify_recording(outcome.mcap_path).legs
    clearance = yaml.safe_load(draft.yaml)["gait"]["options"]["leg_clearance"]
    assert legs.source == "the URDF's collision geometry (coal)"
    assert legs.clearance == clearance == 0.01
    assert legs.distance.shape == (outcome.result.n_nodes,)
    assert legs.smallest >= clearance, (legs.pair, legs.node)


def _directors(q_row, index: int) -> np.ndarray:
    return np.asarray(q_row)[12 * index + 3:12 * index + 12].reshape(3, 3).T


def test_the_rerun_view_draws_the_robots_meshes_moved_by_tf(robot):
    """The .rrd holds the URDF's visual meshes (rerun's URDF loader, package:// resolved)
    and, per node, the /tf transform of the base link between named frames."""
    from rerun.chunk import RrdReader

    urdf, _, outcome = robot
    links = {f.name for f in pin.buildModelFromXML(urdf).frames if f.type == pin.FrameType.BODY}
    columns, base_rows = {}, 0
    base = outcome.result.scene.root.body
    for chunk in RrdReader(outcome.rrd_path).stream():
        path = chunk.entity_path
        if "/visual_geometries/" in path:
            link = path.split("/visual_geometries/")[1].split("/")[0]
            columns.setdefault(link, set()).update(chunk.to_record_batch().schema.names)
        if path == f"/world/robot/frames/{base}":
            base_rows += chunk.num_rows
    meshes = {link for link, names in columns.items() if any("blob" in n for n in names)}
    assert meshes and meshes <= links
    assert base_rows == outcome.result.n_nodes
