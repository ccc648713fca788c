"""The variational integrator against explicit Runge-Kutta methods: energy and trajectory
error against cost, on the same motions.

    .venv/bin/python benchmarks/integrators.py            # short and long horizons
    .venv/bin/python benchmarks/integrators.py --quick    # short horizon only (< 1 min)
    .venv/bin/python benchmarks/integrators.py --long-steps 30000   # a 30 s long horizon

Motions (seed 0, as `benchmarks/free_motion.py`): walker3d hanging from its right heel (the
pose upside down, the heel pinned at its initial position), gravity, seeded random rates,
(a) passive, (b) actuated by the smooth random joint torques of
`gait_planner.dynamics.free_motion.random_torques`.

* VI: `run_free_motion` (director coordinates, the heel held by its contact multipliers),
  dt = 1 ms (on the short horizon also 2 and 0.5 ms), torques held constant on each step
  at their midpoint value.
* RK45 and DOP853 (`scipy.integrate.solve_ivp`) on the continuous model in minimal
  coordinates: a fixed-base Pinocchio model re-rooted at the pinned heel (a spherical joint
  to the world there, then foot, calf, thigh, torso, the other leg; each scene joint keeps
  its type, the knees their axis), joint accelerations by ABA; spherical joints carry a
  unit quaternion, normalised where the right-hand side reads it. The torques are the VI's
  (+m on the scene child, -m on the scene parent of each joint), as generalised forces of
  the same joints of this model (`pinned_model.PinnedModel.rhs`; applied instead as world
  couples through ABA's external forces they gave the same solutions to round-off); the
  state carries their work W. Both models start from the same state (checked: body
  centres of mass and triads, kinetic and potential energy agree to round-off).

Measured per run: wall time of the integration alone (no model building, no evaluation of
the errors) and evaluations (VI: Newton iterations, each a residual and Jacobian; RK: rhs
calls). Energy error |E - W - E(0)| / T_max, with E(0) the continuous energy of the
common initial state, W the work of the torques (zero when passive) and T_max the largest
kinetic energy along the VI run of the same motion and horizon; for the VI, E is the
discrete energy of each step (T of the difference quotient plus the mean potential) and W
the discrete work of the held torques, both at the step's midpoint. Trajectory error
(short horizon only: the motion is chaotic): RMS over the nodes t_n = n dt and the bodies
of the distance of each body's centre of mass from the reference's (DOP853, rtol 1e-13).

Writes benchmarks/results/integrators.json (rows: method, motion, horizon, steps (VI steps,
or intervals of the RK output grid), horizon_s, dt_or_rtol, wall_s, evaluations,
energy_scale_J (T_max), energy_error_max, energy_error_final, the error's median over the
first and over the last tenth of the run, trajectory_error_rms, reference, and a
downsampled energy-error series) and benchmarks/integrators.png, prints a table.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import time
from pathlib import Path
from typing import Callable

import numpy as np
from scipy.integrate import solve_ivp

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.dynamics.free_motion import (energies, pinned_velocity, random_torques,
                                               random_velocity, run_free_motion)
from gait_planner.model.angles import configuration
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.verify.mechanics import parse_scene

from free_motion import hanging
from pinned_model import PinnedModel
from results_io import figure_path, write_results

PIN, SEED, DT = "foot_r_heel", 0, 1e-3
SHORT, LONG = 1_000, 100_000  # steps of DT
REFERENCE_RTOL = 1e-13
# VI time steps (the first is DT, whose run sets T_max) and RK tolerances (rtol = atol),
# chosen so that the RK methods' wall times bracket the VI's at DT.
VI_DTS = {"short": (DT, 2e-3, 5e-4), "long": (DT,)}
RTOLS = {"short": {"RK45": (1e-4, 1e-6, 1e-8, 1e-10), "DOP853": (1e-6, 1e-8, 1e-10, 1e-12)},
         "long": {"RK45": (1e-4, 1e-6, 1e-9), "DOP853": (1e-6, 1e-9, 1e-12)}}
SERIES_POINTS = 400  # energy-error series kept per row (maximum per bin)


@dataclasses.dataclass
class Motion:
    """One motion, set up for both integrators."""

    name: str
    scene: Scene  # hanging walker3d
    mb: Multibody
    pinned: PinnedModel
    q0: np.ndarray  # (k,) director configuration
    p0: np.ndarray  # (k,) the VI's initial momentum M P(q0) nu0
    y0: np.ndarray  # (nq + nv + 1,) Pinocchio state and W = 0
    energy0: float  # continuous E(0), J
    torques: Callable[[float], np.ndarray] | None  # t -> (nt,), N m
    start_check: dict  # how well the two initial states agree


def motion(actuated: bool) -> Motion:
    """The hanging walker3d, passive or actuated, and the check of the common start."""
    scene = hanging(load_scene("walker3d"))
    mb = Multibody(scene)
    rng = np.random.default_rng(SEED)  # drawn as run_free_motion draws them
    q0 = configuration(scene)
    nu0 = pinned_velocity(mb, q0, random_velocity(mb, q0, rng), PIN)
    torques = random_torques(mb, rng) if actuated else None
    qdot0 = np.array(mb.null_space(q0)) @ nu0
    contact = scene.contact(PIN)
    anchor = mb.point_matrix(contact.body, contact.point) @ q0
    pinned = PinnedModel(parse_scene(scene.source), PIN, anchor)
    q, v = pinned.state(q0, qdot0)
    frames = pinned.frames(q)
    position = max(np.abs(frames[b][0] - q0[mb.block(b)][:3]).max() for b in mb.body_names)
    rotation = max(np.abs(frames[b][1] - q0[mb.block(b)][3:].reshape(3, 3).T).max()
                   for b in mb.body_names)
    mech = DiscreteMechanics(mb)
    T_dir = 0.5 * qdot0 @ (mb.mass_diagonal * qdot0)
    V_dir = float(q0 @ mech.gravity_gradient)
    T_pin, V_pin = pinned.energy(q, v)
    # the heel at rest in both: the pinned joint's origin is fixed by construction
    check = {"position_m": position, "triad": rotation, "kinetic_J": abs(T_pin - T_dir),
             "potential_J": abs(V_pin - V_dir), "energy_J": T_dir + V_dir}
    if max(position, rotation) > 1e-12 or abs(T_pin + V_pin - T_dir - V_dir) > 1e-12:
        raise RuntimeError(f"the two models do not start from the same state: {check}")
    return Motion("actuated" if actuated else "passive", scene, mb, pinned, q0,
                  mb.mass_diagonal * qdot0, np.concatenate([q, v, [0.0]]), T_dir + V_dir,
                  torques, check)


def _energy_errors(t: np.ndarray, err: np.ndarray, scale: float) -> dict:
    """A row's energy-error fields: maximum, final value, medians over the first and the
    last tenth of the run (drift: the second grows), and the series of the maximum per bin
    (at most SERIES_POINTS bins)."""
    tenths = np.array_split(err, 10)
    bins = np.array_split(np.arange(t.size), min(SERIES_POINTS, t.size))
    return {"energy_scale_J": scale, "energy_error_max": float(err.max()),
            "energy_error_final": float(err[-1]),
            "energy_error_median_first_tenth": float(np.median(tenths[0])),
            "energy_error_median_last_tenth": float(np.median(tenths[-1])),
            "series": {"t": [float(t[b[-1]]) for b in bins],
                       "energy_error": [float(err[b].max()) for b in bins]}}


def run_vi(m: Motion, dt: float, steps: int,
           scale: float | None = None) -> tuple[dict, np.ndarray]:
    """One VI run: (row without the trajectory error, body centres of mass (N+1, nb, 3)).
    Energy errors relative to `scale` (J; None: this run's largest kinetic energy)."""
    traj, report = run_free_motion(m.scene, steps=steps, dt=dt, gravity=True,
                                   torques="zero" if m.torques is None else "random", seed=SEED,
                                   pin=PIN)
    if np.abs(traj.q[0] - m.q0).max() > 0 or np.abs(traj.p[0] - m.p0).max() > 1e-12:
        raise RuntimeError("run_free_motion did not start from the state set up by motion()")
    T, E = energies(DiscreteMechanics(m.mb), traj)
    work = np.zeros(steps)
    if m.torques is not None:
        force = m.mb.actuation_force.map(steps)
        f = np.array(force(traj.q[:-1].T, traj.tau.T) + force(traj.q[1:].T, traj.tau.T)).T
        dW = 0.5 * np.einsum("ni,ni->n", f, np.diff(traj.q, axis=0))
        work = np.cumsum(dW) - 0.5 * dW  # at the step midpoints, like E
    scale = float(T.max()) if scale is None else scale
    err = np.abs(E - work - m.energy0) / scale
    row = {"method": "VI", "motion": m.name, "steps": steps, "horizon_s": steps * dt,
           "dt_or_rtol": dt, "wall_s": report.wall_time_s,
           "evaluations": int(traj.newton_iterations.sum() + steps),
           **_energy_errors(traj.times[:-1] + 0.5 * dt, err, scale)}
    coms = traj.q.reshape(steps + 1, -1, 12)[:, :, :3]
    return row, coms


def run_rk(m: Motion, method: str, rtol: float, steps: int,
           dt: float = DT) -> tuple[dict, object]:
    """One solve_ivp run: (row without errors, the solution on the nodes n dt)."""
    rhs = m.pinned.rhs(m.torques, m.mb.joint_slices)
    t_nodes = np.arange(steps + 1) * dt
    start = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, t_nodes[-1]), m.y0, method=method, t_eval=t_nodes,
                    rtol=rtol, atol=rtol)
    wall = time.perf_counter() - start
    if sol.status != 0:
        raise RuntimeError(f"{method} rtol {rtol}: {sol.message}")
    return {"method": method, "motion": m.name, "steps": steps, "horizon_s": steps * dt,
            "dt_or_rtol": rtol, "wall_s": wall, "evaluations": int(sol.nfev)}, sol


def rk_errors(m: Motion, row: dict, sol, scale: float) -> None:
    """Fill in the energy errors of an RK row (relative to `scale`, J)."""
    nq, nv = m.pinned.model.nq, m.pinned.model.nv
    E = np.empty(sol.t.size)
    for n, y in enumerate(sol.y.T):
        E[n] = sum(m.pinned.energy(y[:nq], y[nq:nq + nv])) - y[-1]
    err = np.abs(E - m.energy0) / scale
    row.update(_energy_errors(sol.t, err, scale))


def centres(m: Motion, sol) -> np.ndarray:
    """(N+1, nb, 3) body centres of mass along an RK solution, in scene body order."""
    nq = m.pinned.model.nq
    out = np.empty((sol.t.size, m.mb.nb, 3))
    for n, y in enumerate(sol.y.T):
        frames = m.pinned.frames(y[:nq])
        out[n] = [frames[b][0] for b in m.mb.body_names]
    return out


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=-1))))


def horizon(m: Motion, name: str, steps: int) -> list[dict]:
    """Rows of one motion over `steps` steps of DT: the VI at each of VI_DTS[name], each RK
    method and tolerance, and on the short horizon the reference (on the finest VI grid),
    against which the trajectory errors are measured."""
    seconds = steps * DT
    rows, coms = [], []
    for dt in VI_DTS[name]:
        row, c = run_vi(m, dt, round(seconds / dt), rows[0]["energy_scale_J"] if rows else None)
        rows.append(row)
        coms.append(c)
    scale = rows[0]["energy_scale_J"]
    runs = [run_rk(m, method, rtol, steps) for method, rtols in RTOLS[name].items()
            for rtol in rtols]
    if name == "short":
        fine = min(VI_DTS[name])
        runs.append(run_rk(m, "DOP853", REFERENCE_RTOL, round(seconds / fine), fine))
        reference = centres(m, runs[-1][1])
        for row, c in zip(rows, coms):
            row["trajectory_error_rms"] = _rms(c, reference[::round(row["dt_or_rtol"] / fine)])
    for row, sol in runs:
        rk_errors(m, row, sol, scale)
        row["reference"] = row["dt_or_rtol"] == REFERENCE_RTOL
        if name == "short" and not row["reference"]:
            row["trajectory_error_rms"] = _rms(centres(m, sol), reference[::round(DT / fine)])
        rows.append(row)
    for row in rows:
        row.setdefault("trajectory_error_rms", None)
        row.setdefault("reference", False)
        row["horizon"] = name
    return rows


def run(quick: bool = False, long_steps: int = LONG) -> tuple[list[dict], dict]:
    """All rows (short horizon; also the long one unless quick) and the start checks."""
    rows, checks = [], {}
    for actuated in (False, True):
        m = motion(actuated)
        checks[m.name] = m.start_check
        rows += horizon(m, "short", SHORT)
        if not quick:
            rows += horizon(m, "long", long_steps)
    return rows, checks


def print_table(rows: list[dict]) -> None:
    print(f"{'horizon':>7} {'motion':>8} {'method':>7} {'dt/rtol':>8} {'steps':>7} "
          f"{'wall s':>7} {'evals':>8} {'dE max':>9} {'dE final':>9} {'med 1st':>9} "
          f"{'med last':>9} {'traj rms m':>10}")
    for r in rows:
        traj = r["trajectory_error_rms"]
        label = r["method"] + ("*" if r["reference"] else "")
        print(f"{r['horizon']:>7} {r['motion']:>8} {label:>7} {r['dt_or_rtol']:>8.0e} "
              f"{r['steps']:>7} {r['wall_s']:>7.2f} {r['evaluations']:>8} "
              f"{r['energy_error_max']:>9.2e} {r['energy_error_final']:>9.2e} "
              f"{r['energy_error_median_first_tenth']:>9.2e} "
              f"{r['energy_error_median_last_tenth']:>9.2e} "
              + (f"{traj:>10.2e}" if traj is not None else f"{'-':>10}"))
    print("(* the reference, DOP853 rtol 1e-13; dE relative to T_max of the VI run; med 1st, "
          "med last: its median over the first and last tenth of the run; evals: VI Newton "
          "iterations, RK rhs calls)")


def plot(rows: list[dict], path: Path) -> None:
    """Energy error against time per method (longest horizon run), and error against cost."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    longest = "long" if any(r["horizon"] == "long" for r in rows) else "short"
    colours = {"VI": "k", "RK45": "tab:blue", "DOP853": "tab:red"}
    fig, axes = plt.subplots(2, 2, figsize=(12, 8.5))
    for ax, motion_name in zip(axes[0], ("passive", "actuated")):
        chosen = [r for r in rows if r["horizon"] == longest and r["motion"] == motion_name]
        shades = {}
        for r in chosen:
            shades[r["method"]] = shades.get(r["method"], 0) + 1
            style = ("-", "--", ":", "-.", (0, (3, 1, 1, 1, 1, 1)))[shades[r["method"]] - 1]
            label = f"{r['method']} {'dt' if r['method'] == 'VI' else 'rtol'} {r['dt_or_rtol']:.0e}"
            ax.semilogy(r["series"]["t"], np.maximum(r["series"]["energy_error"], 1e-17),
                        linestyle=style, color=colours[r["method"]], label=label, lw=1)
        ax.set(title=f"{motion_name}, {longest} horizon", xlabel="t (s)",
               ylabel="|E - W - E(0)| / T_max")
        ax.legend(fontsize=7)
    for r in rows:
        if r["reference"]:
            continue
        marker = "o" if r["motion"] == "passive" else "s"
        if r["trajectory_error_rms"] is not None:
            axes[1, 0].loglog(r["wall_s"], r["trajectory_error_rms"], marker,
                              color=colours[r["method"]])
        if r["horizon"] == longest:
            axes[1, 1].loglog(r["wall_s"], r["energy_error_max"], marker,
                              color=colours[r["method"]])
    axes[1, 0].set(title="short horizon: trajectory error against cost",
                   xlabel="wall time (s)", ylabel="RMS centre-of-mass error (m)")
    axes[1, 1].set(title=f"{longest} horizon: max energy error against cost",
                   xlabel="wall time (s)", ylabel="max |E - W - E(0)| / T_max")
    for ax in axes[1]:
        for method, colour in colours.items():
            ax.plot([], [], "o", color=colour, label=method)
        ax.plot([], [], "ko", mfc="none", label="o passive, s actuated")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="short horizon only")
    parser.add_argument("--long-steps", type=int, default=LONG,
                        help=f"VI steps of the long horizon (default {LONG})")
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)  # the paper's torso inertia warns on load
    rows, checks = run(args.quick, args.long_steps)
    print_table(rows)
    for name, check in checks.items():
        print(f"common start ({name}): centres of mass {check['position_m']:.1e} m, triads "
              f"{check['triad']:.1e}, T {check['kinetic_J']:.1e} J, V {check['potential_J']:.1e} J "
              f"(E(0) = {check['energy_J']:.3f} J)")
    path = write_results("integrators", rows, {"start_check": checks, "pinned": PIN,
                                               "seed": SEED, "quick": args.quick})
    plot(rows, figure_path("integrators.png"))
    print(f"wrote {path} and {figure_path('integrators.png')}")


if __name__ == "__main__":
    main()
