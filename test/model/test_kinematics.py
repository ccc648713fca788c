"""Director kinematics of every scene: constraints, null space, reparametrisation, actuation.

Properties of docs/design.md sections 1-4 at random configurations q = F_d(u0, q_initial) with
hypothesis-drawn increments (rotations up to 3 rad per joint, so far from the upright pose):

* F_d keeps every internal and joint constraint: g(F_d(u, q)) = 0 to round-off for any u;
* G(q) P(q) = 0, rank G = m, rank P = ndof = k - m;
* dF_d/du (u = 0, q) = P(q) (the reparametrisation's tangent is the null space matrix);
* P^T B^T = [0; I]: joint torques are the generalised forces of the joint rates and do no
  work on the root; B^T tau is internal: no force on any phi, zero net moment.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.model.angles import configuration

ROUND_OFF = 1e-12
SCENES = ("compass", "walker2d", "walker3d")
EXPECTED_SIZES = {  # (k, m, ndof): docs/design.md section 2 for walker3d
    "compass": (24, 20, 4),
    "walker2d": (84, 75, 9),
    "walker3d": (84, 64, 20),
}


def increments(size: int, bound: float = 3.0):
    return st.lists(
        st.floats(-bound, bound, allow_nan=False), min_size=size, max_size=size
    ).map(np.array)


def vectors(seed: int, size: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-3.0, 3.0, size)


def random_configuration(mb, u0: np.ndarray) -> np.ndarray:
    return np.array(mb.reparametrise(u0, configuration(mb.scene))).ravel()


@functools.cache
def reparametrise_jacobian(mb) -> ca.Function:
    u, q = ca.SX.sym("u", mb.ndof), ca.SX.sym("q", mb.k)
    return ca.Function("dFd_du", [u, q], [ca.jacobian(mb.reparametrise(u, q), u)])


def test_sizes(any_model):
    mb = any_model.mb
    assert (mb.k, mb.m, mb.ndof) == EXPECTED_SIZES[any_model.scene.name]
    assert mb.k - mb.m == mb.ndof
    assert mb.nt == mb.ndof - mb.root_dof


def test_initial_configuration_is_consistent(any_model):
    mb = any_model.mb
    q0 = configuration(any_model.scene)
    assert np.abs(np.array(mb.constraints(q0))).max() <= ROUND_OFF


@pytest.mark.parametrize("scene", SCENES)
@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), scale=st.floats(0.0, 1.0))
def test_reparametrisation_keeps_constraints(model, scene, seed, scale):
    mb = model(scene).mb
    rng = np.random.default_rng(seed)
    q = random_configuration(mb, scale * rng.uniform(-3.0, 3.0, mb.ndof))
    for u in (scale * rng.uniform(-3.0, 3.0, mb.ndof), rng.uniform(-3.0, 3.0, mb.ndof)):
        q_next = np.array(mb.reparametrise(u, q)).ravel()
        assert np.abs(np.array(mb.constraints(q_next))).max() <= ROUND_OFF


@pytest.mark.parametrize("scene", SCENES)
@settings(max_examples=20, deadline=None)
@given(data=st.data())
def test_reparametrisation_keeps_constraints_hypothesis_u(model, scene, data):
    """Both increments drawn by hypothesis (its shrinking finds the worst entries)."""
    mb = model(scene).mb
    q = random_configuration(mb, data.draw(increments(mb.ndof), label="u0"))
    u = data.draw(increments(mb.ndof), label="u")
    q_next = np.array(mb.reparametrise(u, q)).ravel()
    assert np.abs(np.array(mb.constraints(q_next))).max() <= ROUND_OFF


@pytest.mark.parametrize("scene", SCENES)
@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_null_space_annihilates_constraint_jacobian(model, scene, seed):
    mb = model(scene).mb
    q = random_configuration(mb, vectors(seed, mb.ndof))
    G = np.array(mb.constraint_jacobian(q))
    P = np.array(mb.null_space(q))
    assert G.shape == (mb.m, mb.k) and P.shape == (mb.k, mb.ndof)
    assert np.abs(G @ P).max() <= ROUND_OFF
    assert np.linalg.matrix_rank(G) == mb.m
    assert np.linalg.matrix_rank(P) == mb.ndof


# matrix-free products (what the optimiser uses) against the matrices they stand for:
# name -> (the matrix at q, the attribute giving the size of x, scale of x)
MATRIX_FREE = {
    "null_space_transpose": (lambda mb, q: np.array(mb.null_space(q)).T, "k", 100.0),
    "actuation_force": (lambda mb, q: np.array(mb.actuation(q)), "nt", 50.0),
}


@pytest.mark.parametrize("product", sorted(MATRIX_FREE))
@pytest.mark.parametrize("scene", SCENES)
@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_matrix_free_products_equal_the_matrix_products(model, scene, product, seed):
    """P(q)^T r (reverse differentiation of the velocity map) and B^T(q) tau (the
    actuation forces applied directly) equal the products with the explicit matrices."""
    mb = model(scene).mb
    matrix, size, scale = MATRIX_FREE[product]
    q = random_configuration(mb, vectors(seed, mb.ndof))
    x = scale * vectors(seed + 1, getattr(mb, size))
    expected = matrix(mb, q) @ x
    got = np.array(getattr(mb, product)(q, x)).ravel()
    assert np.abs(got - expected).max() <= ROUND_OFF * max(1.0, np.abs(expected).max())


@pytest.mark.parametrize("scene", SCENES)
@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_reparametrisation_tangent_is_null_space(model, scene, seed):
    mb = model(scene).mb
    q = random_configuration(mb, vectors(seed, mb.ndof))
    dF = np.array(reparametrise_jacobian(mb)(np.zeros(mb.ndof), q))
    assert np.abs(dF - np.array(mb.null_space(q))).max() <= ROUND_OFF


@pytest.mark.parametrize("scene", SCENES)
@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_joint_torques_are_generalised_forces_of_joint_rates(model, scene, seed):
    mb = model(scene).mb
    q = random_configuration(mb, vectors(seed, mb.ndof))
    PtBt = np.array(mb.null_space(q)).T @ np.array(mb.actuation(q))
    expected = np.vstack([np.zeros((mb.root_dof, mb.nt)), np.eye(mb.nt)])
    assert np.abs(PtBt - expected).max() <= ROUND_OFF


@pytest.mark.parametrize("scene", SCENES)
@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_actuation_is_internal(model, scene, seed):
    """B^T tau puts no force on any centre of mass and its moment
    sum_bodies (phi x f_phi + sum_i d_i x f_di) vanishes, about any point."""
    mb = model(scene).mb
    rng = np.random.default_rng(seed)
    q = random_configuration(mb, rng.uniform(-3.0, 3.0, mb.ndof))
    tau = rng.normal(0.0, 100.0, mb.nt)
    f = (np.array(mb.actuation(q)) @ tau).reshape(mb.nb, 4, 3)
    qb = q.reshape(mb.nb, 4, 3)
    assert np.abs(f[:, 0]).max() == 0.0  # sum over the phi blocks: each one is zero
    director_moment = np.cross(qb[:, 1:], f[:, 1:]).sum(axis=(0, 1))
    assert np.abs(director_moment).max() <= ROUND_OFF * np.abs(tau).max()
    # each body does receive a moment: the test above is not vacuous
    per_body = np.cross(qb[:, 1:], f[:, 1:]).sum(axis=1)
    assert np.abs(per_body).max() > 1e-3 * np.abs(tau).max()  # not trivially zero


@pytest.mark.parametrize("scene", SCENES)
@settings(max_examples=20, deadline=None)
@given(data=st.data())
def test_increment_inverts_the_reparametrisation(model, scene, data):
    """Multibody.increment(q, F_d(u, q)) = u for turns below half a revolution (entries
    within 1.5 rad: a rotation vector of at most 2.6 rad), at configurations far from
    upright; the refinement's start relies on it (`ocp.refine`)."""
    mb = model(scene).mb
    q = random_configuration(mb, data.draw(increments(mb.ndof), label="u0"))
    u = data.draw(increments(mb.ndof, bound=1.5), label="u")
    q_next = np.array(mb.reparametrise(u, q)).ravel()
    np.testing.assert_allclose(mb.increment(q, q_next), u, atol=1e-9)
