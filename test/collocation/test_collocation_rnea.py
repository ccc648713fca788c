"""`benchmarks.collocation.rnea.SpatialModel`: the recursive Newton-Euler equations of
motion in minimal coordinates.

* every Function (dynamics, impact, project, velocity, acceleration, kinetic_energy)
  equals `MinimalModel`'s (derivatives of q(theta) composed with the director mass
  matrix) at random states, torques and director forces, to 1e-9 relative;
* the inverse dynamics equals Pinocchio's RNEA (`verify.continuous.build_model`) mapped
  to theta exactly (no finite differences): Pinocchio's v and a of (theta, w, a) from the
  rigid-body kinematics, Q = J_p^T tau_pin with J_p = dv/dw (v is linear in w);
* the SX expression is smaller than the q(theta) form's.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from benchmarks.collocation.minimal import MinimalModel
from benchmarks.collocation.rnea import SpatialModel, _Kinematics
from gait_planner.model.scene import JointType
from gait_planner.verify.continuous import build_model, pin_configuration
from gait_planner.verify.mechanics import parse_scene

SCENES = ("compass", "walker2d", "walker3d")
NAMES = ("dynamics", "impact", "project", "velocity", "acceleration", "kinetic_energy")


@pytest.mark.parametrize("name", SCENES)
def test_agrees_with_minimal_model(spatial, name):
    sm = spatial(name)
    assert isinstance(sm, MinimalModel)
    rng = np.random.default_rng(5)
    for _ in range(5):
        n, k = sm.n, sm.k
        th = rng.uniform(-1.2, 1.2, n)
        w, a, w2 = (rng.normal(size=n) for _ in range(3))
        tau, f = 30 * rng.normal(size=sm.mb.nt), 50 * rng.normal(size=k)
        args = {"dynamics": (th, w, a, tau, f), "impact": (th, w, w2, f), "project": (th, f),
                "velocity": (th, w), "acceleration": (th, w, a), "kinetic_energy": (th, w)}
        for key in NAMES:
            mine = np.array(getattr(sm, key)(*args[key])).ravel()
            ref = np.array(sm.reference[key](*args[key])).ravel()
            assert np.abs(mine - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max()), key
    for key in ("dynamics", "impact"):
        assert getattr(sm, key).n_instructions() < sm.reference[key].n_instructions()


def _pinocchio_motion(sm: SpatialModel, model: pin.Model, theta, w, a):
    """Pinocchio's (v, a) (nv,) of (theta, w, a): free-flyer twist and its rate in the root
    frame at its centre of mass, spherical joints' relative angular velocity in the child
    frame (and its rate), revolute angle rates."""
    kin = _Kinematics(sm, ca.DM(theta), ca.DM(w), ca.DM(a))
    def arr(x):
        return np.array(ca.DM(x).full()).ravel()

    R = {b: np.array(ca.DM(kin.R[b]).full()) for b in kin.R}
    om, al = ({b: arr(d[b]) for b in d} for d in (kin.om, kin.al))
    root = sm.scene.root.body
    v, acc = np.zeros(model.nv), np.zeros(model.nv)
    Rr, vr, ar = R[root], arr(kin.v[root]), arr(kin.acc[root])
    v_loc, om_loc = Rr.T @ vr, Rr.T @ om[root]
    v[:3], v[3:6] = v_loc, om_loc
    acc[:3], acc[3:6] = Rr.T @ ar - np.cross(om_loc, v_loc), Rr.T @ al[root]
    for j in sm.scene.joints:
        s = model.joints[model.getJointId(j.name)].idx_v
        start = sm.mb.root_dof + sm.mb.joint_slices[j.name].start
        if j.type is JointType.SPHERICAL:
            Rc, c, p = R[j.child], j.child, j.parent
            rel = Rc.T @ (om[c] - om[p])
            v[s:s + 3] = rel
            acc[s:s + 3] = Rc.T @ (al[c] - al[p]) - np.cross(Rc.T @ om[c], rel)
        else:
            v[s], acc[s] = w[start], a[start]
    return v, acc


@pytest.mark.parametrize("name", SCENES)
def test_inverse_dynamics_is_pinocchios_rnea(spatial, name):
    sm = spatial(name)
    sd = parse_scene(sm.scene.source)
    model, _ = build_model(sd)
    data = model.createData()
    rng = np.random.default_rng(9)
    for _ in range(5):
        theta, w, a = rng.uniform(-1.2, 1.2, sm.n), rng.normal(size=sm.n), rng.normal(size=sm.n)
        c = pin_configuration(sd, model, np.array(sm.configuration(theta)).ravel())
        v, acc = _pinocchio_motion(sm, model, theta, w, a)
        J = np.array([_pinocchio_motion(sm, model, theta, e, 0 * e)[0] for e in np.eye(sm.n)]).T
        expected = J.T @ pin.rnea(model, data, c, v, acc)
        mine = np.array(sm.inverse_dynamics(theta, w, a, np.zeros(sm.k))).ravel()
        assert np.abs(mine - expected).max() <= 1e-9 * max(1.0, np.abs(expected).max())
