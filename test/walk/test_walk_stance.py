"""The torso's position carried by the legs on the ground (`gait_planner.walk.stance`), checked
against the rigid-contact dynamics of the walk's own MuJoCo walker.

The walker (`walk.mujoco_model`, the default walker3d plan's /robot_description) is put on a
plan node, pressed 1 mm into the ground so that MuJoCo finds the feet's contacts. The torque
change `position_torques` returns for an acceleration a_task of the torso's centre of mass
goes through the independent computation of the same physics with rigid contacts: the
KKT system [M -J^T; J 0] [da; df] = [S^T dtau; 0] with MuJoCo's mass matrix and contact
Jacobians. Measured (2026-11-30): on a flat foot (heel and forefoot, node 3) the torso gets
0.93 of a forward a_task, with at most 0.03 m/s^2 and 0.03 rad/s^2 it was not asked for
(the rest is the regularisation that keeps the legs' own accelerations small); on one
forefoot (node 12) 0.04: a point foot is a pivot, and no joint can push the torso along
the ground over it.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.walk.reference import planned_joints

    out = tmp_path_factory.mktemp("stance") / "walker3d.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", "walker3d", "--out", str(out), "--no-rrd"],
                   check=True, capture_output=True)
    return planned_joints(read_plan_mcap(out))


def _rigid_response(recording, node: int, a_task: np.ndarray):
    """(the torso's acceleration change (6,) under rigid contacts, the contacts held)."""
    import mujoco

    from gait_planner.walk.controller import stance_jacobians
    from gait_planner.walk.mujoco_model import build_model, plan_qpos
    from gait_planner.walk.reference import Reference
    from gait_planner.walk.stance import position_torques

    ref = Reference.from_recording(recording, 1)
    scene = ref.scene
    wm = build_model(recording, scene, float(recording.metadata["foot_half_width"]), 0.005,
                     5e-4, 0.005, 0.0)
    model, data = wm.model, mujoco.MjData(wm.model)
    data.qpos[:] = plan_qpos(wm, scene.body_index(scene.root.body), ref.q[node],
                             ref.angles[node])
    data.qpos[2] -= 0.001
    mujoco.mj_forward(model, data)
    M = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, M)
    J, J_task = stance_jacobians(model, data, wm)
    assert len(J) > 0
    base = np.setdiff1d(np.arange(model.nv), wm.dof)
    dtau = position_torques(M, J, J_task, a_task, base, wm.dof)
    nf = len(J)
    kkt = np.block([[M, -J.T], [J, np.zeros((nf, nf))]])
    rhs = np.zeros(model.nv + nf)
    rhs[wm.dof] = dtau
    da = np.linalg.lstsq(kkt, rhs, rcond=None)[0][:model.nv]
    return J_task @ da, ref.active[node]


def test_a_flat_foot_pushes_the_torso_along_the_ground(recording):
    a_task = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    got, held = _rigid_response(recording, 3, a_task)
    assert set(held) == {"foot_r_heel", "foot_r_forefoot"}
    assert 0.8 <= got[0] <= 1.0
    assert np.abs(got[1:]).max() < 0.1  # neither sideways, up, nor a turn of the torso


def test_a_point_foot_cannot_push_the_torso_along_the_ground(recording):
    got, held = _rigid_response(recording, 12, np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
    assert held == ("foot_r_forefoot",)
    assert abs(got[0]) < 0.1


def test_nothing_on_the_ground_asks_nothing():
    from gait_planner.walk.stance import position_torques

    M = np.diag([2.0, 2.0, 2.0, 1.0, 1.0, 1.0, 0.5, 0.5])
    dtau = position_torques(M, np.zeros((0, 8)), np.eye(6, 8), np.ones(6), np.arange(6),
                            np.arange(6, 8))
    assert np.array_equal(dtau, np.zeros(2))


def test_a_state_that_is_not_finite_asks_nothing():
    """A diverged simulation (NaN in the state) gets no correction, not an error from the
    least squares: the walk stops on the state itself."""
    from gait_planner.walk.stance import position_torques

    M = np.diag([2.0, 2.0, 2.0, 1.0, 1.0, 1.0, 0.5, 0.5])
    J = np.eye(3, 8)
    M[6, 6] = np.nan
    dtau = position_torques(M, J, np.eye(6, 8), np.ones(6), np.arange(6), np.arange(6, 8))
    assert np.array_equal(dtau, np.zeros(2))
