"""The simulated walker is the planned walker: MuJoCo's inverse dynamics along a recorded plan
(`gait_planner.walk.inverse`) against the plan's efforts.

The MuJoCo model `gait-planner walk` builds (the recording's /robot_description,
`walk.mujoco_model`) is put on the plan's configuration at every inner node, with the
velocities and accelerations the integrator's node equation sees and the plan's ground
wrenches on the feet; the joint torques it needs must be the published efforts.

Measured on the default plans (2026-11-27): max |MuJoCo torque - effort| per joint over the
nodes, of the plan's peak effort (walker3d 105.4 N m, walker2d 103.4 N m):

    scene      away from contact switches     at switches (a switch node or a neighbour)
    walker3d   0.16 % (hip_l_roll)            0.32 %
    walker2d   0.07 % (hip_l)                 0.23 %

That is the discretisation error the continuous certificate measures with Pinocchio
(`verify.continuous`: 0.10 % and 0.26 % for walker3d); MuJoCo's and Pinocchio's torques
differ by at most 0.05 % of the peak. Tolerances: TORQUE = 0.3 % away from switches, the
certificate's own limit (0.2 %, which every published plan meets) plus twice the
MuJoCo-Pinocchio difference; TORQUE_SWITCH = 1 %, three times the measured value at switches.
They fail for a walker that is not the planned one: thighs with 10 % larger moments give
0.59 % (hip_l_pitch), efforts in the wrong convention (the couple's components along the
parent's directors instead of the torques conjugate to the Cardan angles) 94 %.

The torso is the root, so its inertia enters no joint torque, only the floating base's
balance (the walk's model carries the scene's moments, `walk.mujoco_model.set_inertia`):
with the URDF's realisable torso (J1 1.6194 -> 1.4661 kg m^2,
`gait_planner.io.urdf.realisable_inertia`) the plan leaves 2.2 N m of moment on the base,
with the scene's (the paper's) moments 0.20 N m.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

pytest.importorskip("mujoco")

TORQUE = 0.003  # of the peak effort, away from contact switches
TORQUE_SWITCH = 0.01  # of the peak effort, at switches
BASE_FORCE = 0.002  # of the weight (measured 0.04 %: walker3d 0.21 N of 531 N)


@pytest.fixture(scope="module", params=["walker3d", "walker2d"])
def recording(request, tmp_path_factory):
    from gait_planner.io.mcap_reader import read_plan_mcap

    out = tmp_path_factory.mktemp("model") / f"{request.param}.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", request.param, "--out", str(out)], check=True,
                   capture_output=True)
    return read_plan_mcap(out)


def _worst(inv, errors) -> str:
    j = int(np.argmax(errors))
    return f"{inv.joint_names[j]} {100 * errors[j]:.3g} % of the peak {inv.peak:.4g} N m"


def test_mujoco_needs_the_plans_efforts(recording):
    from gait_planner.walk.inverse import plan_inverse

    inv = plan_inverse(recording)
    assert inv.near_switch.any() and (~inv.near_switch).sum() > 10
    assert inv.error().max() <= TORQUE, _worst(inv, inv.error())
    assert inv.error(switches=True).max() <= TORQUE_SWITCH, _worst(inv, inv.error(True))
    force = inv.base[:, :3] if inv.base.shape[1] == 6 else inv.base[:, :2]
    calm = np.linalg.norm(force, axis=1)[~inv.near_switch]
    assert calm.max() <= BASE_FORCE * inv.weight, f"base force {calm.max():.3g} N"


def test_mujoco_bodies_sit_where_the_plan_puts_them(recording):
    import mujoco

    from gait_planner.walk.mujoco_model import build_model, plan_qpos
    from gait_planner.walk.reference import scene_of

    scene = scene_of(recording)
    wm = build_model(recording, scene, 0.05, 0.005, 1e-3, 0.005, 0.0)
    data = mujoco.MjData(wm.model)
    root = scene.body_index(scene.root.body)
    for q, angles in zip(recording.q, recording.positions):
        data.qpos[:] = plan_qpos(wm, root, q, angles)
        mujoco.mj_kinematics(wm.model, data)
        for i, body in enumerate(scene.bodies):
            b = wm.model.body(body.name).id
            assert np.allclose(data.xipos[b], q[12 * i:12 * i + 3], atol=1e-9), body.name
            D = q[12 * i + 3:12 * i + 12].reshape(3, 3).T  # columns d1 d2 d3
            assert np.allclose(data.xmat[b].reshape(3, 3), D, atol=1e-9), body.name
        for c in scene.contacts:
            i, p = scene.body_index(c.body), np.asarray(scene.body(c.body).points[c.point])
            point = q[12 * i:12 * i + 3] + q[12 * i + 3:12 * i + 12].reshape(3, 3).T @ p
            assert np.allclose(data.xpos[wm.model.body(c.name).id], point, atol=1e-9), c.name


def test_the_torso_inertia_only_unbalances_the_base(recording):
    from gait_planner.io.urdf import realisable_inertia
    from gait_planner.walk.inverse import plan_inverse
    from gait_planner.walk.reference import scene_of

    scene = scene_of(recording)
    if scene.name != "walker3d":
        pytest.skip("walker2d's torso turns about d2 only, whose moment the URDF keeps")
    torso = scene.root.body
    planned, urdf = plan_inverse(recording), plan_inverse(
        recording, {torso: realisable_inertia(scene.body(torso).inertia)})
    assert np.allclose(urdf.torque, planned.torque, rtol=0, atol=1e-9 * urdf.peak)
    moment = {name: np.linalg.norm(inv.base[:, 3:], axis=1)[~inv.near_switch].max()
              for name, inv in (("urdf", urdf), ("planned", planned))}
    assert moment["planned"] < 0.5 and moment["urdf"] > 1.0, moment  # N m: 0.20 and 2.2


def test_the_check_fails_for_another_walker(recording):
    from gait_planner.walk.inverse import plan_inverse
    from gait_planner.walk.reference import scene_of

    scene = scene_of(recording)
    thighs = {b.name: tuple(1.1 * np.asarray(b.inertia)) for b in scene.bodies
              if b.name.startswith("thigh")}
    assert len(thighs) == 2
    inv = plan_inverse(recording, thighs)
    assert inv.error().max() > TORQUE, _worst(inv, inv.error())


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(node=st.integers(0, 10 ** 6), leg=st.integers(0, 1),
       shift=st.tuples(*[st.floats(-0.002, 0.002)] * 3))
def test_a_legs_offsets_move_its_foot_by_the_shift_without_turning_it(recording, node, leg,
                                                                      shift):
    """The controller's foot placement and swing height (`walk.controller`): the joint
    offsets of a whole leg (hip to ankle, `hip_legs`) for a shift of at most 2 mm move the
    foot by that shift (in walker2d's plane) to 25 % + 0.1 mm (the damping takes 7 %, a
    bent knee curves the path; a nearly straight leg is left out) and turn it by under 2 mrad
    (the hip's angles alone, as before 2026-11-29, moved walker3d's foot 1.8 mm of a 6.5 mm
    lift)."""
    import mujoco

    from gait_planner.model.angles import angle_names
    from gait_planner.walk.controller import hip_legs, placement_offsets, rotation_error
    from gait_planner.walk.mujoco_model import build_model, plan_qpos
    from gait_planner.walk.reference import scene_of

    scene = scene_of(recording)
    wm = build_model(recording, scene, 0.05, 0.005, 1e-3, 0.005, 0.0)
    model, data = wm.model, mujoco.MjData(wm.model)
    n = node % len(recording.q)
    data.qpos[:] = plan_qpos(wm, scene.body_index(scene.root.body), recording.q[n],
                             recording.positions[n])
    mujoco.mj_fwdPosition(model, data)  # the kinematics and what mj_jacBody reads
    _, contacts, chain = hip_legs(scene, angle_names(scene))[leg]
    foot = model.body(scene.contact(sorted(contacts)[0]).body).id
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    mujoco.mj_jacBody(model, data, jacp, jacr, foot)
    # a nearly straight leg cannot move its foot along itself (walker2d, 2026-11-29: 1.4 of
    # a 2 mm lift): only legs whose foot-position Jacobian's smallest singular value in the
    # walker's plane or space is above 0.1 m/rad (the damping then takes about 1 %)
    rows = [0, 2] if wm.model.nq < 10 else [0, 1, 2]
    assume(np.linalg.svd(jacp[rows][:, wm.dof[chain]], compute_uv=False).min() > 0.1)
    shift = np.array(shift) * (np.array([1.0, 0.0, 1.0]) if wm.model.nq < 10 else 1.0)
    offsets = placement_offsets(jacp[:, wm.dof[chain]], jacr[:, wm.dof[chain]], shift)
    before, turned = data.xpos[foot].copy(), data.xmat[foot].reshape(3, 3).copy()
    data.qpos[wm.qpos[chain]] += offsets
    mujoco.mj_kinematics(model, data)
    moved = data.xpos[foot] - before
    assert np.linalg.norm(moved - shift) <= 0.25 * np.linalg.norm(shift) + 1e-4, (moved, shift)
    assert np.linalg.norm(rotation_error(data.xmat[foot].reshape(3, 3), turned)) < 2e-3


def test_the_plans_rates_at_its_start_are_its_speed_not_half_of_it(recording):
    """The torso loops' references at the walk's first step: the root's and the whole
    body's velocities and the root's angular velocity at t = 0 are those just after and
    those the walk starts with (`Reference.root_rate0`), not the central difference over
    the plan's clipped start (half the speed: a 213 N m kick at a hip in walker2d's first
    step, which decided whether its 50 ms-delayed walk completed)."""
    from gait_planner.walk.reference import Reference

    ref, h = Reference.from_recording(recording, 2), 5e-4
    v0, w0 = ref.root_rate0
    speed = np.linalg.norm(v0)
    for rate in (ref.root_velocity_at, ref.com_velocity_at):
        assert np.linalg.norm(rate(0.0, h) - rate(2 * h, h)) < 0.02 * speed
    assert np.linalg.norm(ref.root_velocity_at(0.0, h) - v0) < 0.05 * speed
    assert np.linalg.norm(ref.root_rate_at(0.0, h) - w0) < 0.05 * max(np.linalg.norm(w0), 1.0)
