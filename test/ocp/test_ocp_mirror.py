"""The mirror commutes with the nodal reparametrisation (`ocp.mirror.increment_mirror`):
mirror(F_d(u, q)) = F_d(M u, mirror(q)), which lets the elements of the mirror image nodes
be the regular elements at mirrored unknowns (`Layout.images`)."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.ocp.guess import kinematic_guess
from gait_planner.ocp.mirror import configuration_mirror, increment_mirror
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.transcription import Transcription


def _setup(name: str):
    scene = load_scene(name)
    mb = Multibody(scene)
    tr = Transcription(DiscreteMechanics(mb), settings_for(scene))
    return mb, tr, kinematic_guess(tr, scene.gait.step_length)


WALKERS = {name: _setup(name) for name in ("walker2d", "walker3d")}


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(sorted(WALKERS)), st.integers(0, 2**32 - 1),
       st.floats(0.0, 1.5), st.floats(-2.0, 2.0))
def test_the_mirror_of_a_turned_configuration_is_the_mirrored_turn(name, seed, size, step):
    """For turns of up to size rad per entry about any node of the kinematic guess, and any
    step length shift: the two sides agree to round-off."""
    mb, _, guess = WALKERS[name]
    rng = np.random.default_rng(seed)
    A, e, _ = configuration_mirror(mb)
    M = increment_mirror(mb)
    q = guess[rng.integers(len(guess))]
    u = size * rng.uniform(-1.0, 1.0, mb.ndof)
    mirrored_turn = np.array(mb.reparametrise(M @ u, A @ q + step * e)).ravel()
    turned_mirror = A @ np.array(mb.reparametrise(u, q)).ravel() + step * e
    assert np.abs(mirrored_turn - turned_mirror).max() <= 1e-13 * (1.0 + abs(step))


@pytest.mark.parametrize("name", sorted(WALKERS))
def test_increment_mirror_is_a_signed_involution_like_the_torque_mirror(name):
    """M is a signed permutation, its own inverse (mirroring twice is the identity), and
    acts on the joints' increments as the torque mirror acts on their torques."""
    mb, tr, _ = WALKERS[name]
    M = increment_mirror(mb)
    assert set(np.unique(np.abs(M))) == {0.0, 1.0}
    assert np.array_equal(np.abs(M).sum(0), np.ones(mb.ndof))
    assert np.array_equal(M @ M, np.eye(mb.ndof))
    assert np.array_equal(M[mb.root_dof:, mb.root_dof:], tr.B)


def test_no_increment_mirror_when_the_root_is_mirrored_into_another_body():
    """The compass's root is a leg, mirrored into the other leg: no M exists (its
    linearisation is no signed permutation), and the transcription keeps mirrored
    element variants."""
    scene = load_scene("compass")
    mb = Multibody(scene)
    assert increment_mirror(mb) is None
    tr = Transcription(DiscreteMechanics(mb), settings_for(scene))
    assert tr.layout.images is None and tr.layout.element_inputs(1.0, 2.0) == (1.0, 2.0)


def test_element_inputs_are_the_mirrored_unknowns_and_references():
    """(xe, pe) for numbers and for CasADi expressions: x and p followed by M u_0, M u_1,
    B T_0 and A qref_0 + s e, A qref_1 + s e."""
    mb, tr, guess = WALKERS["walker3d"]
    rng = np.random.default_rng(3)
    x = rng.standard_normal(tr.x.shape[0])
    qref = guess[: tr.N - 1]
    p = tr.parameters(qref, dataclasses.replace(tr.settings, step_length=0.7,
                                                friction_coefficient=0.8))
    xe, pe = tr.layout.element_inputs(x, p)
    A, e, _ = configuration_mirror(mb)
    nd, nt = mb.ndof, mb.nt
    U = x[: nd * (tr.N - 1)].reshape(tr.N - 1, nd)
    T0 = x[nd * (tr.N - 1) : nd * (tr.N - 1) + nt]
    assert np.array_equal(xe[x.size:], np.concatenate([tr.M @ U[0], tr.M @ U[1], tr.B @ T0]))
    assert np.allclose(pe[p.size:], np.concatenate([A @ qref[0], A @ qref[1]]) + 0.7 * np.tile(e, 2),
                       rtol=0, atol=1e-15)
    xs, ps = ca.MX.sym("x", x.size), ca.MX.sym("p", p.size)
    symbolic = ca.Function("e", [xs, ps], list(tr.layout.element_inputs(xs, ps)))(x, p)
    assert np.array_equal(np.array(symbolic[0]).ravel(), xe)
    assert np.array_equal(np.array(symbolic[1]).ravel(), pe)
