"""Per-node derivative elements (gait_planner.ocp.derivatives) and their compilation.

The element derivatives are checked against CasADi's own derivatives of the whole SX graph
(computed here directly with ca.jacobian / ca.hessian, not through the module), the sum
of element matrices against numpy's (bit for bit) and compiled functions against the
virtual machine.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.ocp.compile import CompileError, compile_functions
from gait_planner.ocp import derivatives
from gait_planner.ocp.derivatives import _entries, _sum, nlp_derivatives
from gait_planner.ocp.guess import kinematic_guess
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.ocp.transcription import Transcription


def _problem(name: str, **overrides):
    scene = load_scene(name)
    s = settings_for(scene, **overrides)
    tr = Transcription(DiscreteMechanics(Multibody(scene)), s)
    rng = np.random.default_rng(7)
    x = 0.05 * rng.standard_normal(tr.x.shape[0])
    x[-tr.S.shape[0]:] = 1.0 + 0.4 * rng.random(tr.S.shape[0])
    qref = kinematic_guess(tr, s.step_length)[: tr.N - 1]
    p = tr.parameters(qref, s)
    lam_g = rng.standard_normal(tr.g.shape[0])
    return tr, x, p, lam_g


def _dense(m) -> np.ndarray:
    return np.array(ca.densify(ca.DM(m)))


# walker2d "human": phase joint limits (node elements of a phase's nodes) and the twist
# regulariser (interval elements of the cost) besides joint limits and joint speeds
HUMAN = {"posture": "human", "twist_regularisation": 0.5}


@pytest.mark.parametrize("name, overrides", [
    ("compass", {"cost": "kinetic_energy"}),
    pytest.param("walker2d", {"cost": "kinetic_energy"}, marks=pytest.mark.slow),
    pytest.param("walker2d", {"cost": "torque_squared"}, marks=pytest.mark.slow),
    pytest.param("walker2d", HUMAN, marks=pytest.mark.slow)])
def test_element_derivatives_equal_casadi_whole_graph(name, overrides):
    tr, x, p, lam_g = _problem(name, **overrides)
    mine = nlp_derivatives(tr)
    xs, ps = ca.SX.sym("x", tr.x.shape[0]), ca.SX.sym("p", tr.p.shape[0])
    f, g = ca.Function("fg", [tr.x, tr.p], [tr.cost, tr.g]).expand()(xs, ps)
    ls = ca.SX.sym("l", tr.g.shape[0])
    reference = ca.Function("ref", [xs, ps, ls], [
        ca.gradient(f, xs), ca.jacobian(g, xs),
        ca.triu(ca.hessian(0.7 * f + ca.dot(ls, g), xs)[0])])
    grad, jac, hess = (_dense(v) for v in reference(x, p, lam_g))
    _, my_grad = mine["grad_f"](x, p)
    _, my_jac = mine["jac_g"](x, p)
    my_hess = mine["hess_lag"](x, p, 0.7, lam_g)
    for ours, theirs in ((my_grad, grad), (my_jac, jac), (my_hess, hess)):
        assert np.abs(_dense(ours) - theirs).max() <= 1e-12 * np.abs(theirs).max()
    assert my_hess.sparsity().is_triu()


@pytest.mark.parametrize("name, overrides", [("walker2d", {}), ("walker2d", HUMAN),
                                             ("walker3d", {}), ("compass", {}),
                                             ("walker3d", {"legs_apart": True})])
def test_elements_and_rest_sum_to_g_and_cost(name, overrides):
    """g and the cost are their elements plus the rest, in every kind of element: contact
    terms, cones and torso bounds of a node, contact rows of an interval, swing clearances
    (walker3d: full contacts with roll bounds; with legs_apart its legs' clearance rows).
    The mirror image nodes N-1 and N are the
    regular elements at mirrored unknowns and references (`Layout.images`) where
    the mirror commutes with the reparametrisation (the walkers), variants of their own
    where it does not (the compass, whose root is mirrored into the other leg)."""
    tr, x, p, _ = _problem(name, **overrides)
    names = {group.function.name() for group in tr.elements}
    if name == "compass":
        assert tr.layout.images is None
        assert {"dynamics_element_mirrored", "dynamics_element_next_mirrored"} <= names
    else:
        assert tr.layout.images is not None and not any("mirrored" in n for n in names)
        assert {"joint_speed_element", "joint_limits_element", "node_rows_phase0",
                "node_rows_phase4", "contact_hold_phase0_element"} <= names
        assert any(n.startswith("clearance_") for n in names)
        assert ("leg_clearance_element" in names) == overrides.get("legs_apart", False)
    g, g_rest, f, f_rest = (np.array(v).ravel() for v in ca.Function(
        "parts", [tr.x, tr.p], [tr.g, tr.g_without_elements, tr.cost, tr.cost_without_elements]
    )(x, p))
    xe, pe = tr.layout.element_inputs(x, p)
    g_sum, f_sum = g_rest.copy(), float(f_rest[0])
    for group in tr.elements:
        for j in range(group.z_index.shape[1]):
            value = np.array(group.function(xe[group.z_index[:, j]], pe[group.p_index[:, j]],
                                            group.constants))
            if group.rows is None:
                f_sum += value.item()
            else:
                g_sum[group.rows[:, j]] += value.ravel()
    assert np.abs(g_sum - g).max() <= 1e-12 * np.abs(g).max()
    assert abs(f_sum - float(f[0])) <= 1e-12 * abs(float(f[0]))


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 4), st.integers(1, 3), st.integers(1, 5), st.integers(1, 3),
       st.integers(0, 2**32 - 1), st.booleans(), st.booleans())
def test_sum_adds_part_after_part_like_numpy(nz, nr, n, parts, seed, upper, signed):
    """_sum of element matrices (with repeated positions within and across elements and
    parts, and with signs: elements of mirror images) is bit for bit numpy's sum: each
    part's entries added in the order of its nonzeros, then the parts' matrices one after
    the other."""
    rng = np.random.default_rng(seed)
    pattern = ca.Sparsity.dense(nz, nz) if upper else ca.Sparsity.dense(nr, nz)
    rows_e, cols_e = pattern.shape
    size = 6
    entries, expected = [], np.zeros((size, size))
    for _ in range(parts):
        row_index = rng.integers(0, size, (rows_e, n))
        col_index = row_index if upper else rng.integers(0, size, (cols_e, n))
        values = rng.standard_normal((rows_e, cols_e, n)) * 10.0 ** rng.integers(-8, 8)
        if upper:  # full symmetric element matrices
            values = values + values.transpose(1, 0, 2)
        mapped = ca.DM(np.hstack([values[:, :, j] for j in range(n)]))
        ones = (np.ones((rows_e, n)), np.ones((cols_e, n)))
        col_sign = rng.choice([-1.0, 1.0], (cols_e, n)) if signed else ones[1]
        row_sign = col_sign if upper else (rng.choice([-1.0, 1.0], (rows_e, n)) if signed
                                           else ones[0])
        entries.append(_entries(ca.MX(mapped), row_index, col_index, pattern,
                                row_sign if signed else None, col_sign if signed else None))
        part = np.zeros((size, size))
        for j in range(n):
            for b in range(cols_e):  # the order of mapped's nonzeros
                for a in range(rows_e):
                    if not upper or row_index[a, j] <= col_index[b, j]:
                        part[row_index[a, j], col_index[b, j]] += \
                            values[a, b, j] * row_sign[a, j] * col_sign[b, j]
        expected = expected + part
    out = ca.Function("s", [], [_sum(entries, (size, size), upper)])()["o0"]
    assert np.array_equal(_dense(out), expected)
    if upper:  # the upper triangle of the symmetric sum
        assert out.sparsity().is_triu()


def test_compiled_functions_agree_and_are_cached(tmp_path):
    tr, x, p, lam_g = _problem("compass")
    group = tr.elements[0]
    fn = group.function
    args = (x[group.z_index[:, 0]], p[group.p_index[:, 0]], group.constants)
    (compiled,) = compile_functions([fn], tmp_path)
    assert float(np.abs(np.array(compiled(*args)) - np.array(fn(*args))).max()) == 0.0
    libraries = sorted(tmp_path.glob("*.so"))
    stamps = [lib.stat().st_mtime_ns for lib in libraries]
    compile_functions([fn], tmp_path)  # found in the cache: nothing rebuilt or added
    assert sorted(tmp_path.glob("*.so")) == libraries
    assert [lib.stat().st_mtime_ns for lib in libraries] == stamps
    assert not list(tmp_path.glob("*.partial")) and not list(tmp_path.glob("tmp*"))


def test_missing_compiler_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler")
    tr, *_ = _problem("compass")
    with pytest.raises(CompileError, match="no C compiler"):
        compile_functions([tr.elements[0].function], tmp_path)


def test_a_cached_library_needs_no_compiler_and_only_a_build_is_announced(tmp_path,
                                                                          monkeypatch):
    """The compiler is needed for what the cache lacks only (a cache `make setup` filled
    serves a machine without one); a build is announced once, with the last build's time."""
    from gait_planner.ocp.compile import Source, compile_sources, last_build

    tr, *_ = _problem("compass")
    fn = tr.elements[0].function
    told = []
    compile_sources([Source.formed(fn)], tmp_path, notify=told.append)
    assert len(told) == 1 and told[0].startswith("compiling up to 1 derivative element to C")
    assert last_build(tmp_path)[0] == 1
    monkeypatch.setenv("CC", "no-such-compiler")
    again = compile_sources([Source.formed(fn)], tmp_path, notify=told.append)
    assert len(told) == 1 and again[0].name() == fn.name()  # loaded, nothing announced
    with pytest.raises(CompileError, match="no C compiler found .* to build what the cache .* lacks"):
        compile_sources([Source.formed(tr.elements[1].function)], tmp_path)


@pytest.mark.slow
def test_compiled_plan_matches_uncompiled(tmp_path, monkeypatch):
    monkeypatch.setenv("GAIT_PLANNER_CACHE", str(tmp_path))
    scene = load_scene("compass")
    plain = plan_once(Planner(), scene, settings_for(scene))
    compiled = plan_once(Planner(), scene, settings_for(scene, compiled=True))
    assert plain.success and compiled.success
    assert compiled.settings["derivatives"] == "per-node elements compiled to C"
    assert abs(compiled.cost_value - plain.cost_value) <= 1e-6 * plain.cost_value
    assert list(tmp_path.glob("*.so"))


def test_compile_failure_falls_back_and_says_so(tmp_path, monkeypatch):
    monkeypatch.setenv("GAIT_PLANNER_CACHE", str(tmp_path))
    monkeypatch.setenv("CC", "no-such-compiler")
    scene = load_scene("compass")
    result = plan_once(Planner(), scene, settings_for(scene, compiled=True))
    assert result.success
    assert "not compiled: no C compiler" in result.settings["derivatives"]


def test_unwritable_cache_is_a_clear_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    tr, *_ = _problem("compass")
    with pytest.raises(CompileError, match="cannot build in"):
        compile_functions([tr.elements[0].function], blocker / "cache")


def test_one_compiled_library_serves_every_base_time_step(tmp_path):
    import dataclasses

    scene = load_scene("compass")
    functions = []
    for dt in (0.01, 0.02):
        s = dataclasses.replace(settings_for(scene), base_time_step=dt)
        functions.append(Transcription(DiscreteMechanics(Multibody(scene)), s).elements[0])
    compile_functions([functions[0].function], tmp_path)
    libraries = sorted(tmp_path.glob("*.so"))
    compile_functions([functions[1].function], tmp_path)
    assert sorted(tmp_path.glob("*.so")) == libraries
    assert functions[1].constants.tolist() == [0.02]


def test_a_large_source_is_interpreted_and_a_cached_one_is_not_formed(tmp_path):
    from gait_planner.ocp.compile import Source, compile_sources

    tr, *_ = _problem("compass")
    fn = tr.elements[0].function  # 1178 operations
    big, small = (Source(fn.name(), f"test {limit}", lambda: fn, interpret_above=limit)
                  for limit in (1000, 2000))
    interpreted, compiled = compile_sources([big, small], tmp_path)
    assert interpreted is fn and compiled is not fn and len(list(tmp_path.glob("*.so"))) == 1

    def unformable():
        raise AssertionError("a cached library was formed again")

    (again,) = compile_sources([Source(fn.name(), "test 2000", unformable,
                                       interpret_above=2000)], tmp_path)
    z = np.linspace(0.1, 0.9, fn.nnz_in(0))
    args = (z, np.ones(fn.nnz_in(1)), np.full(fn.nnz_in(2), 0.02))
    assert np.array_equal(np.array(again(*args)), np.array(fn(*args)))


@pytest.mark.parametrize("interpreted_above", [
    pytest.param(derivatives.INTERPRETED_ABOVE, marks=pytest.mark.slow), 1100])
def test_compiled_vector_derivatives_equal_the_virtual_machine_bit_for_bit(
        tmp_path, monkeypatch, interpreted_above):
    """Groups of at least LANES nodes are compiled as vector passes (ocp.vectorize), with
    a last pass padded by copies of the last node, and the one-node variants compiled or,
    above INTERPRETED_ABOVE operations, interpreted; the matrices, and so IPOPT's iterates,
    are bit for bit those of CasADi's evaluation of the same elements. (The compass's
    variants have 424 to 11 444 operations: compiled at the default; at 1100 the dynamics'
    and the kinetic energy's (1110 and more) are interpreted, and no library is built for
    them, while the smaller ones, the joint limits' Hessian of 1058 among them, are
    compiled.)"""
    from gait_planner.ocp.compile import compile_sources
    from gait_planner.ocp.vectorize import LANES

    monkeypatch.setattr(derivatives, "INTERPRETED_ABOVE", interpreted_above)
    tr, x, p, lam_g = _problem("compass")
    sizes = [group.z_index.shape[1] for group in tr.elements]
    assert any(n >= LANES and n % LANES for n in sizes) and any(n < LANES for n in sizes)
    compiled = nlp_derivatives(tr, lambda sources: compile_sources(sources, tmp_path))
    plain = nlp_derivatives(tr)
    libraries = {lib.name.rsplit("_", 1)[0] for lib in tmp_path.glob("*.so")}
    assert any(name.endswith("_x4") for name in libraries)
    interpreted = {f"{element}_{kind}" for kind in ("jac", "hess") for element in (
        "dynamics_element_mirrored", "dynamics_element_next_mirrored",
        "kinetic_element_next_mirrored")}
    assert "joint_limits_element_mirrored_hess" in libraries
    assert not interpreted & libraries if interpreted_above == 1100 else interpreted <= libraries
    for name, args in (("grad_f", (x, p)), ("jac_g", (x, p)), ("hess_lag", (x, p, 0.7, lam_g))):
        ours, theirs = compiled[name](*args), plain[name](*args)
        for a, b in zip(ours if isinstance(ours, tuple) else [ours],
                        theirs if isinstance(theirs, tuple) else [theirs]):
            assert a.sparsity() == b.sparsity()
            assert np.array_equal(np.array(a.nonzeros()), np.array(b.nonzeros())), name
