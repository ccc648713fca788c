"""Structure preservation and speed of the variational integrator on long free motions.

    .venv/bin/python benchmarks/free_motion.py            # everything (~2.5 min on 2 cores)
    .venv/bin/python benchmarks/free_motion.py --quick    # 10^4 energy steps, ~1 min

Prints four tables:

1. energy: walker3d hanging from its right heel (pinned), passive, gravity, seeded random
   rates; the energy error |E_n - E_0| / max T after 10^3, 10^4, 10^5 steps: its maximum so
   far and its median over the latest decade (no drift: the median stays put, only brief
   fast episodes raise the maximum);
2. momentum: every scene, 10^4 steps without gravity, random internal torques; linear and
   angular momentum errors relative to the size of their terms, constraint violation;
3. speed: steps/s and Newton iterations per step of those runs;
4. overhead: one Newton iteration split into CasADi evaluation and Python around it, and
   the Simulator's buffered evaluation against the previous per-call conversion (same
   process, same trajectory).
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import time

import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.dynamics.free_motion import energies, run_free_motion
from gait_planner.dynamics.forward import SimulationError, Simulator
from gait_planner.model.angles import configuration
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody

SCENES = ("compass", "walker2d", "walker3d")


def hanging(scene):
    """The scene's initial pose turned upside down (pitch pi): it hangs from its feet."""
    pose = dataclasses.replace(scene.initial_pose, root_angles=(0.0, np.pi, 0.0))
    return dataclasses.replace(scene, initial_pose=pose)


def energy_table(steps: int, dt: float, seed: int) -> None:
    scene = hanging(load_scene("walker3d"))
    traj, report = run_free_motion(scene, steps=steps, dt=dt, gravity=True, seed=seed,
                                   pin="foot_r_heel")
    mech = DiscreteMechanics(Multibody(scene))
    T, E = energies(mech, traj)
    err = np.abs(E - E[0]) / T.max()
    print(f"\n1. energy: walker3d hanging from foot_r_heel, passive, gravity, dt = {dt} s, "
          f"seed {seed} ({report.wall_time_s:.0f} s, {steps / report.wall_time_s:.0f} "
          f"steps/s, max T = {T.max():.1f} J)")
    print(f"{'steps':>8} {'t (s)':>8} {'max err [0, n]':>15} {'median (n/10, n]':>17}")
    n = 1000
    while n <= steps:
        print(f"{n:>8} {n * dt:>8.1f} {err[:n].max():>15.3e} "
              f"{np.median(err[n // 10 : n]):>17.3e}")
        n *= 10
    tenths = np.array_split(err, 10)
    print("median per tenth of the run: " + " ".join(f"{np.median(t):.1e}" for t in tenths))
    print("max per tenth of the run:    " + " ".join(f"{t.max():.1e}" for t in tenths))
    print(f"constraint violation max {report.constraint_violation_max:.1e}, "
          f"Newton iterations {report.newton_iterations_mean:.2f}")


def momentum_and_speed_tables(steps: int, dt: float, seed: int) -> None:
    rows = []
    for name in SCENES:
        _, r = run_free_motion(load_scene(name), steps=steps, dt=dt, gravity=False,
                               torques="random", seed=seed)
        rows.append((name, r))
    print(f"\n2. momentum: {steps} steps, dt = {dt} s, no gravity, random torques, seed {seed}"
          " (planar scenes: L_x, L_z, J_y)")
    print(f"{'scene':>9} {'dL/scale':>10} {'dJ/scale':>10} {'dL kg m/s':>10} "
          f"{'max |g|':>9} {'E change':>9}")
    for name, r in rows:
        print(f"{name:>9} {r.linear_momentum_error_max / r.linear_momentum_scale:>10.1e} "
              f"{r.angular_momentum_error_max / r.angular_momentum_scale:>10.1e} "
              f"{r.linear_momentum_error_max:>10.1e} {r.constraint_violation_max:>9.1e} "
              f"{r.energy_error_max:>9.2f}")
    print(f"\n3. speed (the runs of table 2)\n{'scene':>9} {'steps/s':>9} {'Newton/step':>12}")
    for name, r in rows:
        print(f"{name:>9} {steps / r.wall_time_s:>9.0f} {r.newton_iterations_mean:>12.2f}")


def legacy_run(sim: Simulator, q0, nu0, h: float, n: int) -> np.ndarray:
    """The Simulator's loop as it was before buffering (commit 382460e): every Newton
    iteration calls the CasADi Function with numpy arguments and converts its DM results;
    q_next and p_next by three more calls. Returns q (n+1, k)."""
    mb, mech = sim.mb, sim.mech
    q = np.zeros((n + 1, mb.k))
    q[0], p = q0, sim.initial_momentum(q0, nu0)
    x, tau = np.zeros(mb.ndof + sim.nc), np.zeros(mb.nt)
    floor = 4 * np.finfo(float).eps * np.abs(mb.mass_diagonal).max() / h
    for i in range(n):
        w = h if i else h / 2
        tol = max(sim.tolerance * max(1.0, float(np.abs(p).max())),
                  floor * max(1.0, np.abs(q[i]).max()))
        for _ in range(sim.max_iterations):
            res, jac = sim._newton(x, q[i], p, h, w, tau)
            res = np.array(res).ravel()
            if np.abs(res).max() <= tol:
                break
            dx = np.linalg.solve(np.array(jac), res)
            x = x - dx
            if np.abs(dx).max() <= 4 * np.finfo(float).eps * max(1.0, np.abs(x).max()):
                break
        q[i + 1] = np.array(mb.reparametrise(x[: mb.ndof], q[i])).ravel()
        p = mech.momentum(q[i], q[i + 1], h, tau)
    return q


def overhead_table(steps: int, seed: int) -> None:
    print(f"\n4. overhead per Newton iteration and buffered vs per-call evaluation "
          f"({steps} steps, dt = 0.01, no gravity)")
    print(f"{'scene':>9} {'SX instr':>9} {'eval us':>8} {'iter us':>8} {'legacy s':>9} "
          f"{'now s':>7} {'speed-up':>9} {'max |dq|':>9}")
    for name in SCENES:
        scene = dataclasses.replace(load_scene(name), gravity=0.0)
        mb = Multibody(scene)
        sim = Simulator(DiscreteMechanics(mb))
        q0 = configuration(scene)
        nu0 = np.random.default_rng(seed).normal(0.0, 1.0, mb.ndof)
        # pure CasADi evaluation of the Newton residual + Jacobian, through the buffers
        sim._in["q"][:] = q0
        sim._in["h"][0] = sim._in["w"][0] = 0.01
        reps = 2000
        start = time.perf_counter()
        for _ in range(reps):
            sim._newton_eval()
        evaluation = (time.perf_counter() - start) / reps
        legacy, now = [], []
        for _ in range(2):  # interleaved, best of two
            start = time.perf_counter()
            q_legacy = legacy_run(sim, q0, nu0, 0.01, steps)
            legacy.append(time.perf_counter() - start)
            start = time.perf_counter()
            traj = sim.run(q0, nu0, np.full(steps, 0.01))
            now.append(time.perf_counter() - start)
        per_iteration = min(now) / max(1, traj.newton_iterations.sum() + steps)
        print(f"{name:>9} {sim._newton.n_instructions():>9} {evaluation * 1e6:>8.0f} "
              f"{per_iteration * 1e6:>8.0f} {min(legacy):>9.2f} {min(now):>7.2f} "
              f"{min(legacy) / min(now):>9.2f} {np.abs(q_legacy - traj.q).max():>9.1e}")
    print("(iter us: wall time per Newton evaluation in Simulator.run, all Python included; "
          "max |dq|: legacy vs now, round-off amplified by the chaotic motion)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--energy-steps", type=int, default=100_000)
    parser.add_argument("--energy-dt", type=float, default=1e-3)
    parser.add_argument("--momentum-steps", type=int, default=10_000)
    parser.add_argument("--momentum-dt", type=float, default=1e-2)
    parser.add_argument("--overhead-steps", type=int, default=2_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--quick", action="store_true", help="10^4 energy steps only")
    parser.add_argument("--only", choices=("energy", "momentum", "overhead"))
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)  # the paper's torso inertia warns on load
    if args.quick:
        args.energy_steps = 10_000
    try:
        if args.only in (None, "energy"):
            energy_table(args.energy_steps, args.energy_dt, args.seed)
        if args.only in (None, "momentum"):
            momentum_and_speed_tables(args.momentum_steps, args.momentum_dt, args.seed)
        if args.only in (None, "overhead"):
            overhead_table(args.overhead_steps, args.seed)
    except SimulationError as error:
        raise SystemExit(f"free_motion.py: {error}") from None


if __name__ == "__main__":
    main()
