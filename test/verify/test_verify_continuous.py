"""The continuous-dynamics certificate (gait_planner.verify.continuous) against the planner's
own variational integrator.

A motion simulated in director coordinates (gait_planner.dynamics.forward) with gravity and
smooth joint torques, its node torques published as efforts with the planner's conjugate
torques, must be a physical motion of the Pinocchio model built from the same scene file:
torque error and base residual small and shrinking like h^2 (a wrong mass, inertia, joint
point or axis would leave an O(1) error). Then: a planted torque error is found where it
was planted, a perturbed model is detected, the recording's foot wrenches are assembled as
documented, and `gait-planner report` prints the certificate.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest

from gait_planner.dynamics.free_motion import pinned_velocity, random_torques, random_velocity
from gait_planner.dynamics.forward import Simulator
from gait_planner.model.angles import (configuration, conjugate_torques, joint_angles,
                                       spherical_rotation)
from gait_planner.verify.continuous import (LIMITS, build_model, cardan_efforts, certificate,
                                            effort_names, foot_wrenches_of_recording)
from gait_planner.verify.mechanics import Mechanics, SceneData, parse_scene

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"
HORIZON = 0.2  # s
STEPS = (0.004, 0.002, 0.001)  # s


def scene_data(name: str) -> SceneData:
    return parse_scene((SCENES / f"{name}.yaml").read_text())


@dataclasses.dataclass(frozen=True)
class Motion:
    """A simulated motion in the certificate's inputs (arrays over nodes 0..N)."""

    data: SceneData
    times: np.ndarray
    q: np.ndarray
    efforts: np.ndarray
    wrenches: dict
    active: tuple


def simulate(model, name: str, h: float, contact: str | None = None) -> Motion:
    """`name` from its scene pose with seeded rates (0.3 rad/s) and smooth torques
    (3 x free_motion.random_torques), with gravity, optionally with `contact` held; the node
    torque of node n is the one the discrete equation applied there:
    (h_{n-1} tau_{n-1} + h_n tau_n) / (h_{n-1} + h_n) of the piecewise-constant torques."""
    m = model(name)
    sim = Simulator(m.mech, contacts=(contact,) if contact else ())
    rng = np.random.default_rng(3)
    q0 = configuration(m.scene)
    nu0 = 0.3 * random_velocity(m.mb, q0, rng)
    if contact:
        nu0 = pinned_velocity(m.mb, q0, nu0, contact)
    torques = random_torques(m.mb, rng)
    n = int(round(HORIZON / h))
    run = sim.run(q0, nu0, np.full(n, h), lambda t: 3.0 * torques(t))
    tau = np.zeros((n + 1, m.mb.nt))
    tau[1:-1] = 0.5 * (run.tau[:-1] + run.tau[1:])  # equal steps
    tau[0], tau[-1] = run.tau[0], run.tau[-1]
    data = scene_data(name)
    assert tuple(n for j in m.scene.joints for n in j.angle_names) == effort_names(data)
    wrenches = {}
    if contact:
        body = data.contacts[contact][0]
        C = Mechanics(data).contact_matrix(contact)
        W = np.zeros((n + 1, 6))
        for i, lam in enumerate(run.multipliers):  # node i's ground force (x, z in 2D)
            F = lam if lam.size == 3 else np.array([lam[0], 0.0, lam[1]])
            W[i] = np.concatenate([F, np.cross(C @ run.q[i], F)])
        wrenches[body] = W
    efforts = conjugate_torques(m.scene, joint_angles(m.scene, run.q), tau)
    held = (contact,) if contact else ()
    return Motion(data, run.times, run.q, efforts, wrenches, (held,) * (n + 1))


def certify(motion: Motion, data: SceneData | None = None, efforts=None):
    return certificate(data or motion.data, motion.times, motion.q,
                       motion.efforts if efforts is None else efforts, motion.wrenches,
                       motion.active)


def slope(values) -> float:
    return float(np.polyfit(np.log(STEPS), np.log(values), 1)[0])


# ----------------------------------------------------------------------------- the model


def test_cardan_efforts_are_the_planners_conjugate_torques(model):
    """Pinocchio's spherical torque (child components) -> efforts = conjugate_torques."""
    scene = model("walker3d").scene
    rng = np.random.default_rng(11)
    for _ in range(20):
        angles = rng.uniform(-1.2, 1.2, len(effort_names(scene_data("walker3d"))))
        tau = rng.normal(0.0, 50.0, angles.size)  # parent-director components / about axis
        expected = conjugate_torques(scene, angles, tau)
        i = 0
        for joint in scene.joints:
            if joint.dof == 3:
                R_rel = spherical_rotation(*angles[i:i + 3])
                got = cardan_efforts(R_rel, R_rel.T @ tau[i:i + 3])
                np.testing.assert_allclose(got, expected[i:i + 3], rtol=0, atol=1e-11)
            i += joint.dof


def test_model_takes_the_scene_as_written():
    """Free flyer + 4 spherical + 2 revolute; the paper's non-realisable torso inertia is
    accepted; gravity -9.81 e_z (also Pinocchio's default)."""
    assert np.allclose(pin.Model().gravity.linear, [0.0, 0.0, -9.81])
    data = scene_data("walker3d")
    model, joint_of = build_model(data)
    assert (model.nq, model.nv) == (7 + 4 * 4 + 2, 6 + 4 * 3 + 2)
    assert np.allclose(model.gravity.linear, [0.0, 0.0, -9.81])
    torso = model.inertias[joint_of["torso"]]
    assert np.allclose(np.diag(torso.inertia), [1.6194, 1.0876, 0.3785])  # J1 > J2 + J3
    assert np.isclose(sum(model.inertias[i].mass for i in range(1, model.njoints)),
                      sum(b.mass for b in data.bodies))
    planar, _ = build_model(scene_data("walker2d"))
    assert (planar.nq, planar.nv) == (7 + 6, 6 + 6)


# ----------------------------------------------------------------------------- agreement


@pytest.mark.parametrize("name, contact", [("walker3d", None), ("walker3d", "foot_r_forefoot"),
                                           ("walker2d", None), ("compass", "foot_l")])
def test_agrees_with_the_variational_integrator_at_second_order(model, name, contact):
    certs = [certify(simulate(model, name, h, contact)) for h in STEPS]
    torque = [float(np.abs(c.torque_error).max()) for c in certs]
    force = [float(c.base_force.max()) for c in certs]
    assert 1.8 < slope(torque) < 2.3, torque
    assert 1.8 < slope(force) < 2.3, force
    finest = certs[-1]
    assert finest.ok, finest.summary()
    assert finest.max_torque_calm < 0.5 * LIMITS["torque"]  # 0.02 % (walker3d)
    assert finest.max_force_calm < 1e-5 * finest.weight
    assert not finest.near_switch.any() and finest.wrench_source == "recorded"
    if contact and name == "walker3d":  # the ground force matters: without it, O(1) errors
        without = dataclasses.replace(simulate(model, name, STEPS[-1], contact), wrenches={})
        assert certify(without).max_torque_calm > 100 * finest.max_torque_calm


def impact(model, h: float) -> tuple[Motion, int]:
    """walker3d in free flight (seeded as `simulate`) until node k = N/2, then its right
    forefoot held where it is from node k on: a plastic impact at node k, whose discrete
    impulse w_k F_k is in the published wrench of node k. Returns (motion, k)."""
    m, contact = model("walker3d"), "foot_r_forefoot"
    free, held = Simulator(m.mech), Simulator(m.mech, contacts=(contact,))
    rng = np.random.default_rng(3)
    q0 = configuration(m.scene)
    nu0 = 0.3 * random_velocity(m.mb, q0, rng)
    torques = random_torques(m.mb, rng)
    n = int(round(HORIZON / h))
    k = n // 2
    data = scene_data("walker3d")
    C = Mechanics(data).contact_matrix(contact)
    q, tau = np.zeros((n + 1, m.mb.k)), np.zeros((n, m.mb.nt))
    W = np.zeros((n + 1, 6))
    q[0], p = q0, free.initial_momentum(q0, nu0)
    x = np.zeros(m.mb.ndof + 1)
    for i in range(n):
        tau[i] = 3.0 * torques((i + 0.5) * h)
        sim = free if i < k else held
        guess = np.zeros(m.mb.ndof + sim.nc)
        guess[:m.mb.ndof] = x[:m.mb.ndof]
        x, q[i + 1], _ = sim.step(q[i], p, h, h if i else h / 2, tau[i], guess)
        p = m.mech.momentum(q[i], q[i + 1], h, tau[i])
        if i >= k:
            W[i] = np.concatenate([x[m.mb.ndof:], np.cross(C @ q[i], x[m.mb.ndof:])])
    node_tau = np.zeros((n + 1, m.mb.nt))
    node_tau[1:-1] = 0.5 * (tau[:-1] + tau[1:])
    efforts = conjugate_torques(m.scene, joint_angles(m.scene, q), node_tau)
    active = tuple(() if i < k else (contact,) for i in range(n + 1))
    return Motion(data, np.arange(n + 1) * h, q, efforts, {"foot_r": W}, active), k


def test_an_impact_node_is_certified_too(model):
    """At the impact node the error falls like h (the averaged velocity terms; with C(v_n)
    it would stay at ~0.5 N m), next to it like h^2; the impulse is ~0.3 N s."""
    at, beside = [], []
    for h in STEPS:
        motion, k = impact(model, h)
        cert = certify(motion)
        assert list(cert.nodes[cert.near_switch]) == [k - 1, k, k + 1]
        errors = np.abs(cert.torque_error).max(axis=1)
        at.append(errors[k - 1])
        beside.append(max(errors[k - 2], errors[k]))
        assert 0.25 < np.linalg.norm(motion.wrenches["foot_r"][k, :3]) * h < 0.4  # N s
    assert at[-1] < 0.005 and 0.8 < slope(at) < 1.3, at  # N m
    assert 1.7 < slope(beside) < 2.3, beside


# ----------------------------------------------------------------------------- detection


def test_a_planted_torque_error_is_found_where_it_was_planted(model):
    motion = simulate(model, "walker3d", STEPS[-1])
    clean = certify(motion)
    names = effort_names(motion.data)
    node, joint = 77, names.index("hip_l_roll")
    efforts = motion.efforts.copy()
    efforts[node, joint] += 2.0  # N m
    planted = certify(motion, efforts=efforts)
    worst = np.unravel_index(np.abs(planted.torque_error).argmax(), planted.torque_error.shape)
    assert (planted.nodes[worst[0]], worst[1]) == (node, joint)
    assert planted.torque_error[worst] == pytest.approx(
        clean.torque_error[worst] - 2.0, abs=1e-12)
    assert clean.ok and not planted.ok
    assert "away from switches" in planted.summary() and "FAILED" in planted.summary()

    # at a contact switch (contact set changes at node 77) the error counts there instead
    active = tuple(() if n < node else ("foot_l_heel",) for n in range(len(motion.times)))
    switched = certify(dataclasses.replace(motion, active=active), efforts=efforts)
    assert list(switched.nodes[switched.near_switch]) == [node - 1, node, node + 1]
    assert switched.max_torque_calm == pytest.approx(clean.max_torque_calm, rel=0.5)
    assert switched.max_torque_switch > 0.5


@pytest.mark.parametrize("body, change", [("thigh_r", {"mass": 6.5233 * 1.05}),
                                          ("calf_l", {"inertia": (0.0391 * 1.1, 0.0393, 0.0029)}),
                                          ("foot_r", {"points_shift": 0.01})])
def test_a_wrong_model_is_detected(model, body, change):
    """5 % mass, 10 % inertia, 1 cm joint point on a limb: the torque error jumps."""
    motion = simulate(model, "walker3d", STEPS[-1])
    clean = certify(motion)
    if "points_shift" in change:
        old = motion.data.bodies[motion.data.body_index(body)].points["ankle"]
        wrong = old + [change["points_shift"], 0.0, 0.0]
        joints = tuple(dataclasses.replace(j, child_point=wrong) if j.child == body else j
                       for j in motion.data.joints)
        data = dataclasses.replace(motion.data, joints=joints)
    else:
        bodies = tuple(dataclasses.replace(b, **change) if b.name == body else b
                       for b in motion.data.bodies)
        data = dataclasses.replace(motion.data, bodies=bodies)
    wrong = certify(motion, data=data)
    assert not wrong.ok
    assert wrong.max_torque_calm > 5 * clean.max_torque_calm


def test_a_wrong_root_inertia_shows_in_the_base_moment(model):
    """The root's inertia enters no joint torque, only the base residual moment."""
    motion = simulate(model, "walker3d", STEPS[-1])
    clean = certify(motion)
    bodies = tuple(dataclasses.replace(b, inertia=(1.6194, 1.0876 * 1.1, 0.3785))
                   if b.name == "torso" else b for b in motion.data.bodies)
    wrong = certify(motion, data=dataclasses.replace(motion.data, bodies=bodies))
    assert wrong.max_moment_calm > 10 * clean.max_moment_calm


# ----------------------------------------------------------------------------- recordings


def test_foot_wrenches_from_point_forces_and_from_recorded_wrenches():
    data = scene_data("walker3d")
    points = np.array([[0.1, -0.1, 0.0], [0.35, -0.1, 0.0]])
    forces = np.array([[10.0, 2.0, 300.0], [-5.0, 1.0, 100.0]])
    rec = SimpleNamespace(times=np.zeros(2),
                          contact_names=(("foot_r_heel", "foot_r_forefoot"), ()),
                          contact_points=(points, np.zeros((0, 3))),
                          contact_force_vectors=(forces, np.zeros((0, 3))),
                          wrench_bodies=((), ()))  # a recording made before the wrenches
    wrenches, source = foot_wrenches_of_recording(rec, data)
    assert source == "point forces"
    expected = np.concatenate([forces.sum(axis=0), np.cross(points, forces).sum(axis=0)])
    np.testing.assert_allclose(wrenches["foot_r"][0], expected)
    assert not wrenches["foot_r"][1].any() and not wrenches["foot_l"].any()

    # the recorded per-foot wrench (about its reference point, roll moment included) wins
    p = np.array([0.2, -0.1, 0.0])
    about_p = np.concatenate([forces.sum(axis=0),
                              np.cross(points - p, forces).sum(axis=0) + [7.0, 0.0, 0.0]])
    rec.wrench_bodies = (("foot_r",), ())
    rec.wrench_points = (p[None], np.zeros((0, 3)))
    rec.wrenches = (about_p[None], np.zeros((0, 6)))
    wrenches, source = foot_wrenches_of_recording(rec, data)
    assert source == "recorded"
    np.testing.assert_allclose(wrenches["foot_r"][0], expected + [0, 0, 0, 7.0, 0, 0])


def test_report_prints_the_certificate_of_a_compass_plan(tmp_path, capsys):
    """Plan the compass (about 1 s), record it, and run `gait-planner report` on it."""
    from gait_planner.cli import main
    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.io.mcap_writer import write_plan_mcap
    from gait_planner.model.loader import load_scene
    from gait_planner.ocp.settings import settings_for
    from gait_planner.ocp.solve import Planner
    from gait_planner.strategies import plan_once
    from gait_planner.verify.recorded import certificate_of_recording

    scene = load_scene("compass")
    path = write_plan_mcap(plan_once(Planner(), scene, settings_for(scene)),
                           tmp_path / "compass.mcap")
    rec = read_plan_mcap(path)
    cert = certificate_of_recording(rec)
    has_wrenches = any(len(b) for b in getattr(rec, "wrench_bodies", ()))
    assert cert.wrench_source == ("recorded" if has_wrenches else "point forces")
    assert cert.near_switch.any()
    assert cert.torque_error.shape == (len(cert.nodes), 1)
    main(["report", str(path), "--png", str(tmp_path / "compass.png")])
    out = capsys.readouterr().out
    # the report's continuous-dynamics group, once, with the certificate's numbers
    assert out.count("continuous dynamics (Pinocchio inverse dynamics") == 1
    assert f"{100 * cert.max_torque_calm:.3g} %" in out and f"{cert.max_force_calm:.3g} N" in out
    assert (tmp_path / "compass.png").is_file()
