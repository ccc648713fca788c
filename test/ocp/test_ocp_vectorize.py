"""The vector rewrite of CasADi's map code (gait_planner.ocp.vectorize): bit for bit the
results of CasADi's own evaluation, for every construct the SX code generator emits and for
the planner's real derivative elements."""

from __future__ import annotations

import tempfile
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.ocp.compile import Source, compile_sources, vector_flags
from gait_planner.ocp.derivatives import _element_derivatives
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.transcription import Transcription
from gait_planner.ocp.vectorize import LANES, Unsupported, vectorize_map


def _every_construct() -> ca.Function:
    """Arithmetic with constants, comparisons, logic, if_else, C library functions and
    CasADi's helpers (casadi_sq, casadi_fmax, casadi_fmin, casadi_sign, casadi_fabs)."""
    x = ca.SX.sym("x", 3)
    a, b, c = x[0], x[1], x[2]
    out = ca.vertcat(
        ca.sin(a * b) + ca.cos(c) / 4.0 - 3.5 * a, a**2, ca.sqrt(ca.fmax(a, 1e-4)),
        ca.fmin(a, b), ca.sign(a) * c, ca.fabs(b), ca.atan2(a, b), ca.exp(-a), ca.log(1 + c**2),
        ca.if_else(a > 0.1, ca.tanh(b), ca.floor(c)), ca.logic_and(a > 0, b < 0),
        ca.logic_or(a >= 0, b <= 0), ca.logic_not(a == b), a != b, ca.power(ca.fabs(a), b))
    y = ca.SX.sym("y", out.shape[0])
    return ca.Function("every_construct", [x, y],
                       [out, ca.hessian(ca.dot(y, out), x)[0]], ["x", "y"], ["f", "h"])


@pytest.fixture(scope="module")
def compiled_every_construct():
    fn = _every_construct()
    mapped = fn.map("every_construct_x4", "serial", LANES, [], [])
    with tempfile.TemporaryDirectory() as folder:
        (ext,) = compile_sources([Source(mapped.name(), "test every construct",
                                         lambda: mapped, LANES)], Path(folder))
        yield mapped, ext


def test_every_construct_is_rewritten():
    code = ca.CodeGenerator("c.c", {"with_header": False})
    code.add(_every_construct().map("every_construct_x4", "serial", LANES, [], []))
    rewritten = vectorize_map(code.dump(), LANES)
    assert "vreal" in rewritten and "for (i=0; i<4; ++i)" not in rewritten


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-3, 3, allow_nan=False), min_size=3 * LANES, max_size=3 * LANES),
       st.integers(0, 2**32 - 1), st.booleans())
def test_vector_pass_is_bit_for_bit_casadi(compiled_every_construct, values, seed, equal):
    """Equal entries too (a == b, a != b and the if_else branches switch across lanes)."""
    mapped, ext = compiled_every_construct
    x = np.array(values).reshape(3, LANES)
    if equal:
        x[1, ::2] = x[0, ::2]
    y = np.random.default_rng(seed).standard_normal((mapped.size1_in(1), LANES))
    for ours, theirs in zip(ext(x, y), mapped(x, y)):
        a, b = np.array(ours), np.array(theirs)
        assert np.array_equal(a, b, equal_nan=True)


def _plain_map():
    x = ca.SX.sym("x")
    return ca.Function("plain", [x], [3 * ca.sin(x) + ca.inf]).map("plain_x4", "serial", LANES,
                                                                    [], [])


def test_unknown_statement_is_unsupported():
    code = ca.CodeGenerator("c.c", {"with_header": False})
    code.add(_plain_map())
    text = code.dump()
    assert "vreal" in vectorize_map(text, LANES)  # -casadi_inf and the rest are known
    kernel_end = text.index("  return 0;\n}")
    with pytest.raises(Unsupported, match="casadi_clear"):
        vectorize_map(text[:kernel_end] + "  casadi_clear(w, 3);\n" + text[kernel_end:], LANES)
    with pytest.raises(Unsupported, match="no map over 4"):
        vectorize_map(ca.CodeGenerator("d.c", {"with_header": False}).dump(), LANES)


def test_unsupported_code_is_built_as_casadis_loop(tmp_path, monkeypatch):
    def refuse(code, lanes):
        raise Unsupported("test")

    monkeypatch.setattr("gait_planner.ocp.vectorize.vectorize_map", refuse)
    mapped = _plain_map()
    (ext,) = compile_sources([Source(mapped.name(), "test loop", lambda: mapped, LANES)],
                             tmp_path)
    x = np.linspace(-2, 2, LANES)[None, :]
    assert np.array_equal(np.array(ext(x)), np.array(mapped(x)))


def test_vector_flags_forbid_contraction():
    assert "-ffp-contract=off" in vector_flags()


@pytest.mark.parametrize("name", ["compass", "walker2d",
                                  pytest.param("walker3d", marks=pytest.mark.slow)])
def test_every_element_of_the_planner_is_rewritten(name):
    """No element derivative falls back to CasADi's loop (generating the code only)."""
    scene = load_scene(name)
    tr = Transcription(DiscreteMechanics(Multibody(scene)), settings_for(scene))
    vector = [d for group in tr.elements if group.z_index.shape[1] >= LANES
              for d in _element_derivatives(group)]
    assert vector
    for src in vector:
        code = ca.CodeGenerator(f"{src.name}.c", {"with_header": False})
        code.add(src.make())
        assert "vreal" in vectorize_map(code.dump(), src.lanes), src.name
