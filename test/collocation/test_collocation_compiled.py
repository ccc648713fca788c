"""The collocation's compiled form (`collocation.elements`, `collocation.solve.collocation_nlp`
with compiled=True) against its interpreted form (CasADi's derivatives of the one expanded
SX graph), walker2d on 2 intervals per phase, at a perturbed guess:

* the elements and the rest add up to g and to the cost;
* the element derivatives, in CasADi's virtual machine and compiled to C (the library
  cache, `ocp.compile`), are CasADi's Jacobian, gradient and Lagrangian Hessian to
  round-off;
* a compiled walker2d plan converges and passes the checks the interpreted one passes
  (`test_collocation_plans`).
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np
import pytest

from benchmarks.collocation import plan_collocation
from benchmarks.collocation.elements import mirror_map
from benchmarks.collocation.guess import initial_guess
from benchmarks.collocation.mesh import mesh_of
from benchmarks.collocation.solve import collocation_nlp
from benchmarks.collocation.transcription import CollocationTranscription
from gait_planner.model.loader import load_scene
from gait_planner.ocp.derivatives import expand_nlp, nlp_derivatives
from gait_planner.ocp.settings import settings_for
from gait_planner.verify import verify_result

from test_collocation_plans import NOT_SHARED


@functools.cache
def _point(spatial_model, overrides: tuple = ()):
    """(tr, x, p, lam_g) of walker2d on 2 intervals per phase at a perturbed guess."""
    scene = load_scene("walker2d")
    s = settings_for(scene, **dict(overrides))
    tr = CollocationTranscription(spatial_model, s, mesh_of(scene, s, 2))
    rng = np.random.default_rng(3)
    x = initial_guess(tr, s.step_length, "linear") + 0.01 * rng.standard_normal(tr.x.shape[0])
    p = np.array([s.step_length, s.friction_coefficient])
    return tr, x, p, rng.standard_normal(tr.g.shape[0])


def _dense(m) -> np.ndarray:
    return np.array(ca.densify(ca.DM(m)))


def _reference(tr, x, p, lam_g):
    """CasADi's (g, jac_g, grad_f, upper Hessian) of the interpreted form at x."""
    _, ref, used = collocation_nlp(tr, compiled=False)
    assert used == "CasADi, whole SX graph"
    return (_dense(ref["jac_g"](x, p)[0]), _dense(ref["jac_g"](x, p)[1]),
            _dense(ref["grad_f"](x, p)[1]), np.triu(_dense(ref["hess_lag"](x, p, 1.0, lam_g))))


def _assert_same(mine: dict, tr, x, p, lam_g):
    g, jac, grad, hess = _reference(tr, x, p, lam_g)
    assert np.abs(_dense(mine["jac_g"](x, p)[0]) - g).max() <= 1e-12 * max(1.0, np.abs(g).max())
    for value, expected in ((_dense(mine["jac_g"](x, p)[1]), jac),
                            (_dense(mine["grad_f"](x, p)[1]), grad),
                            (np.triu(_dense(mine["hess_lag"](x, p, 1.0, lam_g))), hess)):
        assert value.shape == expected.shape
        assert np.abs(value - expected).max() <= 1e-11 * max(1.0, np.abs(expected).max())


@pytest.mark.parametrize("overrides", [(), (("cost", "torque_squared"),
                                            ("twist_regularisation", 0.5))])
def test_elements_and_rest_add_up_to_the_nlp(spatial, overrides):
    tr, x, p, _ = _point(spatial("walker2d"), overrides)
    assert tr.layout is not None and tr.elements
    f, f_rest, g, g_rest = (np.array(v).ravel() for v in ca.Function(
        "fg", [tr.x, tr.p], [tr.cost, tr.cost_without_elements, tr.g, tr.g_without_elements]
    )(x, p))
    xe, pe = tr.layout.element_inputs(x, p)
    for e in tr.elements:
        for j in range(e.z_index.shape[1]):
            r = np.array(e.function(xe[e.z_index[:, j]], pe[e.p_index[:, j]],
                                    e.constants)).ravel()
            if e.rows is None:
                f_rest = f_rest + r
            else:
                g_rest[e.rows[:, j]] += r
    assert np.abs(g_rest - g).max() <= 1e-12 * np.abs(g).max()
    assert abs(f_rest[0] - f[0]) <= 1e-12 * abs(f[0])


@pytest.mark.parametrize("overrides", [(), (("cost", "torque_squared"),
                                            ("twist_regularisation", 0.5))])
def test_element_derivatives_are_casadis(spatial, overrides):
    tr, x, p, lam_g = _point(spatial("walker2d"), overrides)
    _assert_same(nlp_derivatives(tr, None, expand_nlp(tr)), tr, x, p, lam_g)


@pytest.mark.slow
def test_compiled_derivatives_are_casadis(spatial):
    tr, x, p, lam_g = _point(spatial("walker2d"))
    _, mine, used = collocation_nlp(tr, compiled=True)
    assert used == "per-point elements compiled to C"
    _assert_same(mine, tr, x, p, lam_g)


def test_the_compass_mirror_is_not_a_permutation_and_stays_interpreted(spatial):
    assert mirror_map(spatial("walker2d")) is not None
    assert mirror_map(spatial("compass")) is None
    scene = load_scene("compass")
    s = settings_for(scene)
    tr = CollocationTranscription(spatial("compass"), s, mesh_of(scene, s, 2))
    assert tr.layout is None and tr.elements == []
    _, _, used = collocation_nlp(tr, compiled=True)
    assert used.startswith("CasADi, whole SX graph (not compiled")


@pytest.mark.slow
def test_compiled_plan_converges_and_passes_the_checks():
    scene = load_scene("walker2d")
    result = plan_collocation(scene, settings_for(scene, compiled=True))
    assert result.success, result.message
    assert result.settings["derivatives"] == "per-point elements compiled to C"
    assert result.stats.max_constraint_violation < 1e-10
    report = verify_result(result)
    failures = [f for f in report.failures if not f.startswith(NOT_SHARED)]
    assert not failures, report.summary()
