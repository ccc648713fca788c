"""Grid refinement (`gait_planner.ocp.refine`, `gait_planner.strategies.plan_certified`): a plan
that misses the continuous-dynamics certificate is planned again on a grid twice as fine,
from itself, and the refined plan passes."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

from gait_planner.model.loader import load_scene
from gait_planner.memory import gigabytes
from gait_planner.ocp import solve
from gait_planner.ocp.refine import first_interval, refined_memory, refined_settings, refined_start
from gait_planner.ocp.settings import SettingsError, settings_for
from gait_planner.ocp.solution import violations
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.ocp.transcription import Transcription
from gait_planner.strategies import plan_certified
from gait_planner.verify.certify import continuous_certificate
from gait_planner.verify import verify_result


@pytest.fixture(scope="module")
def coarse_walker2d():
    """walker2d on 3 intervals per phase (the hard case "coarse grid"), planned cold with
    no refinement: it converges and misses the certificate (0.27 % of the peak torque
    away from switches, 2026-11-23)."""
    scene = load_scene("walker2d")
    settings = settings_for(scene, intervals_per_phase=3, refinements=0)
    planner = Planner()
    result = plan_once(planner, scene, settings, warm_start=False)
    assert result.success, result.message
    return scene, settings, planner, result


def test_refined_settings_keep_the_half_cycle():
    s = settings_for(load_scene("walker3d"))
    fine = refined_settings(s)
    assert fine.intervals == tuple(2 * i for i in s.intervals)
    assert sum(fine.intervals) * fine.base_time_step == pytest.approx(
        sum(s.intervals) * s.base_time_step, rel=1e-15)


def _refined(coarse_walker2d):
    """(coarse, fine transcriptions, x0, qref, p) of the refined start from the plan of
    `coarse_walker2d`."""
    _, settings, planner, _ = coarse_walker2d
    built = planner._built[next(iter(planner._built))]
    coarse, plan = built.tr, built.stored[-1]
    fine = Transcription(coarse.mech, refined_settings(settings))
    x0, qref = refined_start(coarse, plan, fine, settings)
    return coarse, fine, x0, qref, fine.parameters(qref, refined_settings(settings))


def test_refined_start_keeps_the_coarse_plan_at_shared_nodes(coarse_walker2d):
    result = coarse_walker2d[3]
    coarse, fine, x0, qref, p = _refined(coarse_walker2d)
    assert x0.shape == (int(fine.x.shape[0]),) and qref.shape == (fine.N - 1, coarse.mb.k)
    Q, TAU, h = (np.array(v) for v in ca.Function("f", [fine.x, fine.p],
                                                  [fine.Q, fine.TAU, fine.h])(x0, p))
    # every phase but the last: fine node 2j is coarse node j (the last is compressed so
    # that both grids end on the image of node 0: `coarse_times`)
    last = first_interval(coarse, coarse.phase_of_interval[-1])
    shared = np.arange(0, 2 * last + 1, 2)
    np.testing.assert_allclose(Q[:, shared].T, result.q[shared // 2], atol=1e-12)
    np.testing.assert_allclose(TAU[:, shared].T, result.tau[shared // 2], atol=1e-9)
    np.testing.assert_allclose(2 * h.ravel()[::2], np.diff(result.times), rtol=1e-12)
    np.testing.assert_allclose(Q[:, fine.N - 1], result.q[coarse.N - 1], atol=1e-12)
    # every reference configuration is admissible (the null space method needs it)
    assert max(float(np.abs(np.array(coarse.mb.constraints(q))).max()) for q in qref) < 1e-12


def test_refined_start_moves_between_the_coarse_nodes(coarse_walker2d):
    """No fine interval of the start stands still, and its discrete Euler-Lagrange rows are
    within 1 kN (FORCE_SCALE) in every phase: 0.54-0.64 kN at the impacts, where a start
    standing at each coarse node for a coarse interval left 5.9-6.7 kN (2026-11-27)."""
    _, fine, x0, _, p = _refined(coarse_walker2d)
    Q, g = (np.array(v) for v in ca.Function("f", [fine.x, fine.p], [fine.Q, fine.g])(x0, p))
    assert np.abs(np.diff(Q, axis=1)).max(axis=0).min() > 1e-4
    worst = violations(fine, g.ravel())
    dynamics = {name: v for name, v in worst.items() if name.startswith("dynamics")}
    assert dynamics and max(dynamics.values()) < 1.0, dynamics


def test_refined_start_refuses_a_grid_that_is_not_a_refinement(coarse_walker2d):
    scene, settings, planner, _ = coarse_walker2d
    built = planner._built[next(iter(planner._built))]
    other = Transcription(built.tr.mech, settings_for(scene, intervals_per_phase=4))
    with pytest.raises(ValueError, match="not a refinement"):
        refined_start(built.tr, built.stored[-1], other, settings)


def test_refinements_must_be_a_small_whole_number():
    scene = load_scene("walker2d")
    for bad in (-1, 4, 1.5, True):
        with pytest.raises(SettingsError, match="refinements"):
            settings_for(scene, refinements=bad)


@pytest.mark.slow
def test_a_plan_that_misses_the_certificate_is_refined_until_it_passes(coarse_walker2d):
    scene, settings, _, coarse = coarse_walker2d
    assert not continuous_certificate(coarse).ok
    # since the strike-speed bound (2026-11-27) one refinement (30 intervals, 0.238 %) is
    # not enough; the second (60) passes with 0.063 %
    result, cert = plan_certified(Planner(), scene, dataclasses.replace(settings, refinements=2),
                                  warm_start=False)
    assert result.success, result.message
    assert result.n_nodes - 1 == 4 * (coarse.n_nodes - 1)
    assert cert.ok, cert.summary()
    assert cert.max_torque_calm < 0.5 * continuous_certificate(coarse).max_torque_calm
    # the same half cycle up to one interval of each grid (15: 0.56 s, 60: 0.59 s)
    assert result.duration == pytest.approx(coarse.duration, rel=0.06)
    assert "torque error (of peak) away from switches" in result.settings["refinement"]
    assert result.stats.iterations > coarse.stats.iterations  # both plans counted
    assert verify_result(result).continuous.ok


@pytest.mark.slow
def test_a_failed_refinement_is_not_restarted_and_the_coarse_plan_stands(coarse_walker2d,
                                                                         monkeypatch):
    """With the inertia-free attempt and the continued one capped at 3 iterations, the
    coarse plan converges only through the restart with the inertia test, and its
    refinement fails both ways (barrier fixed from 1e-4, then as a cold plan's first
    attempt): it is not restarted with the inertia test (`strategies.REFINE_ATTEMPTS`;
    walker3d's 1.0 m step spent 590 s in such a restart), and the coarse plan is returned
    with the reason."""
    scene, settings, _, _ = coarse_walker2d
    for variant in ("cold", "continued"):
        monkeypatch.setitem(solve.VARIANTS, variant,
                            {**solve.VARIANTS[variant], "ipopt.max_iter": 3})
    result, cert = plan_certified(Planner(), scene, dataclasses.replace(settings, refinements=1),
                                  warm_start=False)
    assert result.success, result.message
    assert "restarted with IPOPT's inertia test" in result.settings["initial_guess"]
    assert result.n_nodes - 1 == sum(settings.intervals) and not cert.ok
    note = result.settings["refinement"]
    refined = note.split(f"refined to {2 * sum(settings.intervals)}: ")[1]
    assert refined.startswith("IPOPT: iteration limit reached") and "after 6 iterations" in refined


@pytest.mark.slow
def test_without_refinements_the_plan_is_returned_as_planned(coarse_walker2d):
    scene, settings, _, coarse = coarse_walker2d
    result, cert = plan_certified(Planner(), scene, settings, warm_start=False)
    assert result.n_nodes == coarse.n_nodes and not cert.ok
    assert "refinement" not in result.settings


@pytest.mark.slow
@pytest.mark.xfail(reason="open regression since the strike-speed bound (2026-11-27): the "
                   "refined walker2d plan still zigzags or misses a check; benchmarks/HISTORY.md",
                   strict=False)
def test_a_plan_whose_efforts_zigzag_is_refined():
    """walker2d on 6 intervals per phase passes the certificate, but the swing knee's effort
    wobbles as it reaches its 75 deg limit (-7.9, -5.0, -9.6, -5.1 N m at nodes 26-29); on
    12 per phase, refined from it, no effort zigzags (2026-11-23)."""
    scene = load_scene("walker2d")
    settings = settings_for(scene, intervals_per_phase=6, refinements=1)
    result, cert = plan_certified(Planner(), scene, settings, warm_start=False)
    assert result.success, result.message
    assert "efforts zigzag" in result.settings["refinement"]
    assert result.n_nodes - 1 == 60
    report = verify_result(result)
    assert report.ok, report.failures


@pytest.mark.slow
@pytest.mark.xfail(reason="open since the ground became parameters (2026-11-28): the cold start "
                   "now reaches another local minimum (J 1477.68 on 80 intervals, 0.708 % on the "
                   "certificate; its 160-interval refinement stops at the iteration cap), the "
                   "same problem to round-off; benchmarks/HISTORY.md", strict=False)
def test_walker3d_torque_squared_passes_every_check_after_refinement():
    """The hard case that misses the certificate on its own grid (the swing leg's large
    accelerations before toe-off, an O(h^2) error): refined from its own optimum, it passes
    every check. Which local minimum the cold start finds, and so how many refinements it
    needs, moves with round-off: 2026-11-23 0.47 % on 40 intervals, 0.099 % on 80 (J
    1018.46, ~25 s); 2026-11-25 0.84 % on 40, 0.211 % on 80, passing on 160 (J 1072.15,
    729 iterations, ~46 s). With the strike-speed bound (2026-11-27) its refinement missed
    the certificate within 200 s until the refined start moved between the coarse nodes
    (`ocp.refine`); since then it passes again (~60 s)."""
    scene = load_scene("walker3d")
    settings = settings_for(scene, cost="torque_squared", compiled=True, max_solve_time=200.0)
    result, cert = plan_certified(Planner(), scene, settings, warm_start=False)
    assert result.success, result.message
    assert result.n_nodes - 1 in [f * sum(settings.intervals)
                                  for f in (2, 4)[: settings.refinements]]
    assert cert.ok, cert.summary()
    report = verify_result(result)
    assert report.ok, report.failures


def test_a_refinement_the_machine_has_no_memory_for_is_not_built(coarse_walker2d, monkeypatch):
    """With less memory available than the refined grid's build is expected to take (twice
    what the coarse problem kept, `refined_memory`), the grid is not refined: the coarse
    plan is returned, the note says how much was needed and available, and no problem is
    built (G1 refined to 160 intervals grew a CI process to 24.3 GB and it was killed)."""
    scene, settings, _, coarse = coarse_walker2d
    settings = dataclasses.replace(settings, refinements=1)
    planner = Planner()  # no other problem to forget (`Planner.make_room`)
    planner.build(scene, settings, ())
    kept = planner.memory_kept(scene, settings)
    assert kept > 1e6  # walker2d's problem on 3 intervals a phase: tens of MB
    monkeypatch.setattr(solve, "available_bytes", lambda: refined_memory(kept) - 1)
    built = set(planner._built)
    result, cert = plan_certified(planner, scene, settings)
    assert result.n_nodes == coarse.n_nodes and not cert.ok
    note = result.settings["refinement"]
    assert (f"not refined to {2 * sum(settings.intervals)}: its problem would take about "
            f"{gigabytes(refined_memory(kept))} to build" in note), note
    assert set(planner._built) == built
