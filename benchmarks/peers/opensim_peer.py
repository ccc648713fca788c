"""OpenSim Moco peer (issue #27): problem.json -> plan.npz, the gait problem written as Moco's
own predictive example (example2DWalking's gait prediction) writes half a gait cycle: a
MocoStudy on the walker as an OpenSim Model with compliant sphere-ground contact
(benchmarks/peers/opensim_walker.py), solved by MocoCasADiSolver (Hermite-Simpson
collocation, IPOPT, CasADi's finite differences and a limited-memory Hessian: Moco's
defaults). Run in the opensim env from the repository root:

    .venv-peers/opensim/bin/python -m benchmarks.peers.opensim_peer PROBLEM.json PLAN.npz \\
        --intervals 8 [--time-limit 300] [--start guess|dmocc] [--max-iterations 1000]

The problem (each line Moco's own way of saying it):
* time: [0, T], T = DMOCC's half cycle (the sum of its phase durations), fixed. Moco could
  free T (setTimeBounds) but not the phases: it has no contact schedule, so the phase
  durations DMOCC imposes are not expressible; the mesh is DMOCC's grid (setMesh at
  DMOCC's node times over T when --intervals is the problem's grid, the phases' uniform
  grid otherwise), so Moco's mesh points are DMOCC's nodes;
* cost: MocoControlGoal, the integral of the squared controls, i.e. of the squared joint
  efforts (CoordinateActuators of optimal force 1): DMOCC's "squared_torque";
* mirror periodicity: MocoPeriodicityGoal (an endpoint constraint) pairing each coordinate
  value and speed at the end with its mirror partner's at the start (problem["mirror"];
  negated where the mirror negates), the controls likewise (as the example pairs its
  lumbar actuator); base x is left out of it and bounded instead: initial x = DMOCC's
  node 0, final x = that + the step (a final-state bound; with the mirror of every other
  coordinate this is DMOCC's x shift, and the average speed DMOCC's);
* bounds: joint ranges as coordinate bounds, the joint speed limit as speed bounds, the
  torso lean as bounds on the base's pitch (and roll) Euler angle(s); efforts +-1000 N m;
* contact: compliant spheres (opensim_walker), no schedule, no placements, no cones (the
  smoothed Coulomb law keeps |f_t| near mu f_n but its viscous term may exceed it), no
  impacts; not expressed either: the swing clearance, the strike-speed bound.
* guess: problem["guess"] (DMOCC's kinematic guess: coordinates, moved in x to start at
  DMOCC's start, speeds by finite differences, zero efforts) or, with --start dmocc, DMOCC's plan (coordinates, speeds by
  finite differences, its efforts), interpolated onto Moco's guess grid.
* IPOPT's tolerances are the example's (convergence and constraint 1e-4), its iteration cap
  --max-iterations (the example's 1000). Moco has no time limit: the solve runs in a forked
  process; at --time-limit (wall clock, from the end of the build) the file Moco polls
  between iterations (delete_this_to_stop_optimization_*.txt) is deleted, which stops IPOPT
  and returns the current iterate as an unconverged solution; should that not happen within
  STOP_GRACE s the process is killed and the plan is the last iterate Moco wrote (every
  OUTPUT_INTERVAL iterations: solver output_interval), not converged.

The plan: nodes at DMOCC's node times (Moco's mesh points, else linear interpolation of
Moco's Hermite-Simpson trajectory), q from the coordinates (`Walker.to_exchange`),
tau_nodes the controls there, force:<contact> each SmoothSphereHalfSpaceForce's force on
its sphere at the node's state, phase_of_node DMOCC's (Moco has no phases of its own).
"""

from __future__ import annotations

import argparse
import glob
import json
import multiprocessing
import os
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.peers import exchange
from benchmarks.peers.opensim_walker import Walker, osim

OUTPUT_INTERVAL = 5  # IPOPT iterations between the iterates Moco writes (time limit)
STOP_GRACE = 30.0  # s after the time limit for Moco to stop and write its solution
TOLERANCE = 1e-4  # example2DWalking's convergence and constraint tolerances
BASE_SPEED = 10.0  # m/s or rad/s, the base speeds' bounds (none in DMOCC)


def node_grid(problem: dict, intervals: int) -> tuple[np.ndarray, np.ndarray]:
    """(Moco's mesh times (M+1,) s, DMOCC's node times (K+1,) s the plan is given at)."""
    out = np.asarray(problem["dmocc"]["times"], float)
    if all(p["intervals"] in (intervals, intervals - 1) for p in problem["phases"]) and \
            problem["phases"][0]["intervals"] == intervals:
        return out, out
    mesh, _ = exchange.phase_grid(problem, intervals)
    return mesh * out[-1] / mesh[-1], out


def _vector(values) -> osim.Vector:
    out = osim.Vector(len(values), 0.0)
    for k, v in enumerate(values):
        out.set(k, float(v))
    return out


def build_study(problem: dict, walker: Walker, intervals: int, start: str,
                max_iterations: int, output_dir: Path, threads: int = 1) -> osim.MocoStudy:
    """The MocoStudy (module docstring), its guess set; threads: the solver's parallel
    jobs (1: none, `set_parallel(0)`; 0: Moco's default, every core)."""
    study = osim.MocoStudy()
    study.setName("gait_half_cycle")
    mp = study.updProblem()
    mp.setModelAsCopy(walker.model)
    mesh, _ = node_grid(problem, intervals)
    T = float(mesh[-1])
    mp.setTimeBounds(0.0, T)
    # bounds
    q0 = walker.from_exchange(problem["dmocc"]["q"][0])
    x0 = float(q0[walker.coordinates.index("base_x")])
    step = float(problem["mirror"]["base"]["x_shift"])
    lean = np.radians(problem.get("torso_lean_max_deg", 45.0))
    base_bounds = {"base_x": [x0 - 0.5, x0 + step + 0.5], "base_y": [-0.5, 0.5],
                   "base_z": [0.3, 2.0], "base_rz": [-lean, lean] if walker.planar
                   else [-0.5, 0.5], "base_rx": [-lean, lean], "base_ry": [-lean, lean]}
    for name in walker.base_coordinates:
        if name == "base_x":
            mp.setStateInfo(walker.value_path(name), base_bounds[name], x0, x0 + step)
        else:
            mp.setStateInfo(walker.value_path(name), base_bounds[name])
        mp.setStateInfo(walker.speed_path(name), [-BASE_SPEED, BASE_SPEED])
    limit = float(problem["joint_speed_limit"])
    for name in walker.joint_names:
        lo, hi = problem["joint_ranges"].get(name, [-np.pi, np.pi])
        mp.setStateInfo(walker.value_path(name), [lo, hi])
        mp.setStateInfo(walker.speed_path(name), [-limit, limit])
    # goals
    mp.addGoal(osim.MocoControlGoal("effort", 1.0))
    symmetry = osim.MocoPeriodicityGoal("symmetry")
    for name, (partner, sign) in walker.mirror_signs().items():
        paths = [walker.speed_path] if name == "base_x" else \
            [walker.value_path, walker.speed_path]
        for path in paths:
            pair = osim.MocoPeriodicityGoalPair(path(name), path(partner))
            pair.set_negate(sign < 0)
            symmetry.addStatePair(pair)
        if name in walker.joint_names:
            pair = osim.MocoPeriodicityGoalPair(walker.actuator_path(name),
                                                walker.actuator_path(partner))
            pair.set_negate(sign < 0)
            symmetry.addControlPair(pair)
    mp.addGoal(symmetry)
    # solver
    solver = study.initCasADiSolver()
    solver.set_transcription_scheme("hermite-simpson")
    solver.setMesh(osim.StdVectorDouble([float(t) for t in mesh / T]))
    solver.set_optim_solver("ipopt")
    solver.set_optim_convergence_tolerance(TOLERANCE)
    solver.set_optim_constraint_tolerance(TOLERANCE)
    solver.set_optim_max_iterations(max_iterations)
    solver.set_output_interval(OUTPUT_INTERVAL)
    solver.set_verbosity(2)
    if threads:  # Moco's property: 0 not parallel, 1 every core, N > 1 N jobs
        solver.set_parallel(0 if threads == 1 else threads)
    solver.setGuess(make_guess(problem, walker, solver, start))
    os.chdir(output_dir)  # Moco writes its iterates in the working directory
    return study


def make_guess(problem: dict, walker: Walker, solver, start: str) -> osim.MocoTrajectory:
    """Moco's guess on its own grid: the kinematic guess or DMOCC's plan (coordinates,
    speeds by finite differences, efforts zero or DMOCC's)."""
    source = problem["guess" if start == "guess" else "dmocc"]
    times = np.asarray(source["times"], float)
    values = np.array([walker.from_exchange(q) for q in source["q"]])
    values[:, :len(walker.base_coordinates)] = np.unwrap(
        values[:, :len(walker.base_coordinates)], axis=0)
    x = walker.coordinates.index("base_x")
    # the kinematic guess starts elsewhere in x: moved to DMOCC's start, which the bounds fix
    values[:, x] += walker.from_exchange(problem["dmocc"]["q"][0])[x] - values[0, x]
    speeds = np.gradient(values, times, axis=0, edge_order=2)
    guess = solver.createGuess("bounds")
    grid = np.array([guess.getTimeMat()[k] for k in range(guess.getNumTimes())])
    for k, name in enumerate(walker.coordinates):
        guess.setState(walker.value_path(name), _vector(np.interp(grid, times, values[:, k])))
        guess.setState(walker.speed_path(name), _vector(np.interp(grid, times, speeds[:, k])))
    efforts = np.asarray(problem["dmocc"]["tau_nodes"], float) if start == "dmocc" else \
        np.zeros((len(times), len(walker.joint_names)))
    for k, name in enumerate(walker.joint_names):
        guess.setControl(walker.actuator_path(name),
                         _vector(np.interp(grid, times, efforts[:, k])))
    return guess


def _child(problem_path: str, intervals: int, start: str, max_iterations: int,
           work: str, threads: int) -> None:
    """The forked solve: build.json after the build, solution.sto and solve.json after the
    solve (in `work`)."""
    t0 = time.perf_counter()
    problem = exchange.read_problem(problem_path)
    walker = Walker(problem)
    study = build_study(problem, walker, intervals, start, max_iterations, Path(work),
                        threads)
    build_time = time.perf_counter() - t0
    Path(work, "build.json").write_text(json.dumps({"build_time": build_time}))
    t1 = time.perf_counter()
    solution = study.solve()
    solve_time = time.perf_counter() - t1
    converged = bool(solution.success())
    solution.unseal()  # a failed (or stopped) solve's solution is sealed
    info = {"solve_time": solve_time, "converged": converged,
            "status": solution.getStatus(), "iterations": int(solution.getNumIterations()),
            "objective": float(solution.getObjective())}
    solution.write(str(Path(work, "solution.sto")))
    Path(work, "solve.json").write_text(json.dumps(info))


def solve(problem_path: Path, intervals: int, start: str, max_iterations: int,
          time_limit: float, work: Path, threads: int = 1) -> tuple[osim.MocoTrajectory, dict]:
    """Run the forked solve with the wall-clock limit; (trajectory, info)."""
    work.mkdir(parents=True, exist_ok=True)
    for old in glob.glob(str(work / "*")):
        if Path(old).is_file():
            os.unlink(old)
    context = multiprocessing.get_context("fork")
    child = context.Process(target=_child, args=(str(problem_path.resolve()), intervals,
                                                  start, max_iterations, str(work),
                                                  threads))
    t0 = time.perf_counter()
    child.start()
    deadline, limited = None, False
    while child.is_alive():
        if deadline is None and (work / "build.json").exists():
            deadline = time.perf_counter() + time_limit
        if deadline is not None and time.perf_counter() > deadline:
            if not limited:  # Moco's own stop: delete the file it polls between iterations
                limited = True
                for stop in glob.glob(str(work / "delete_this_to_stop_optimization_*")):
                    os.unlink(stop)
            elif time.perf_counter() > deadline + STOP_GRACE:
                child.kill()
                break
        time.sleep(0.2)
    child.join()
    wall = time.perf_counter() - t0
    build = json.loads((work / "build.json").read_text()) if (work / "build.json").exists() \
        else {"build_time": float("nan")}
    if (work / "solve.json").exists():
        info = json.loads((work / "solve.json").read_text())
        if limited:
            info["status"] = f"time limit {time_limit:g} s: {info['status']}"
        return osim.MocoTrajectory(str(work / "solution.sto")), {**build, **info}
    iterates = sorted(glob.glob(str(work / "**" / "*.sto"), recursive=True),
                      key=os.path.getmtime)
    why = f"time limit {time_limit:g} s" if limited else \
        f"solver process exit {child.exitcode}"
    if not iterates:
        raise RuntimeError(f"{why}, no iterate written")
    name = Path(iterates[-1]).stem
    digits = "".join(ch for ch in name.split("_")[-1] if ch.isdigit())
    return osim.MocoTrajectory(iterates[-1]), {
        **build, "solve_time": wall - build.get("build_time", 0.0), "converged": False,
        "status": f"{why}; last iterate {Path(iterates[-1]).name}",
        "iterations": int(digits) if digits else -1, "objective": float("nan")}


def control_integral(walker: Walker, trajectory: osim.MocoTrajectory) -> float:
    """The integral of the squared controls over the trajectory (trapezoid rule on its
    time points, Hermite-Simpson's midpoints included): MocoControlGoal's value."""
    times = np.array([trajectory.getTimeMat()[k] for k in range(trajectory.getNumTimes())])
    total = np.zeros(len(times))
    for joint in walker.joint_names:
        values = trajectory.getControlMat(walker.actuator_path(joint))
        total += np.array([values[k] for k in range(len(times))]) ** 2
    return float(np.sum(0.5 * (total[1:] + total[:-1]) * np.diff(times)))


def to_plan(problem: dict, walker: Walker, trajectory: osim.MocoTrajectory,
            intervals: int, meta: dict) -> exchange.Plan:
    """Moco's trajectory at DMOCC's node times as an exchange.Plan."""
    _, nodes = node_grid(problem, intervals)
    times = np.array([trajectory.getTimeMat()[k] for k in range(trajectory.getNumTimes())])
    nodes = nodes * times[-1] / nodes[-1]

    def column(kind: str, path: str) -> np.ndarray:
        values = trajectory.getStateMat(path) if kind == "state" else \
            trajectory.getControlMat(path)
        return np.interp(nodes, times, np.array([values[k] for k in range(len(times))]))

    values = np.column_stack([column("state", walker.value_path(c))
                              for c in walker.coordinates])
    speeds = np.column_stack([column("state", walker.speed_path(c))
                              for c in walker.coordinates])
    tau = np.column_stack([column("control", walker.actuator_path(j))
                           for j in walker.joint_names])
    forces = {c: np.zeros((len(nodes), 3)) for c in problem["contact_frames"]}
    for n in range(len(nodes)):
        walker.set_coordinates(values[n], speeds[n])
        for c in forces:
            forces[c][n] = walker.contact_force(c)
    phase_of_node = np.zeros(len(nodes), dtype=int)
    k = 0
    for p, phase in enumerate(problem["phases"]):
        phase_of_node[k:k + phase["intervals"] + 1] = p
        k += phase["intervals"]
    return exchange.Plan(times=nodes, q=np.array([walker.to_exchange(v) for v in values]),
                         phase_of_node=phase_of_node, meta=meta, tau_nodes=tau,
                         forces=forces)


NOTES = ("duration DMOCC's total, fixed (no phases: Moco has no contact schedule); contact"
         " compliant (SmoothSphereHalfSpaceForce spheres, example2DWalking's parameters),"
         " no placements, no hard cones (smoothed Coulomb plus viscous friction), no impacts;"
         " periodicity hard (mirror, MocoPeriodicityGoal endpoint constraint, controls"
         " included); joint ranges, joint speed limit, torso lean (base Euler angles) as"
         " bounds; efforts within +-1000 N m; not expressed: swing clearance, strike-speed"
         " bound; the scene's torso inertia (inertia_overrides) used")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("problem", type=Path)
    parser.add_argument("plan", type=Path)
    parser.add_argument("--intervals", type=int, default=8, help="intervals per phase")
    parser.add_argument("--time-limit", type=float, default=300.0, help="s")
    parser.add_argument("--start", choices=("guess", "dmocc"), default="guess")
    parser.add_argument("--max-iterations", type=int, default=1000)
    parser.add_argument("--threads", type=int, default=1,
                        help="the solver's parallel jobs: 1 none (the default), 0 Moco's "
                             "default (every core; OMP_NUM_THREADS does not change it)")
    args = parser.parse_args(argv)
    plan_path = args.plan.resolve()
    problem = exchange.read_problem(args.problem)
    work = plan_path.with_suffix(".moco")
    trajectory, info = solve(args.problem, args.intervals, args.start, args.max_iterations,
                             args.time_limit, work, args.threads)
    walker = Walker(problem)
    if not np.isfinite(info["objective"]):  # a stopped solve: its cost at the last iterate
        info["objective"] = control_integral(walker, trajectory)
    for iterate in sorted(glob.glob(str(work / "MocoCasADiSolver_*.sto")))[:-1]:
        os.unlink(iterate)  # keep the last iterate only
    meta = {"peer": "opensim", "version": osim.__version__, "solver": "MocoCasADiSolver ipopt",
            "formulation": "direct collocation (Hermite-Simpson, Moco), explicit multibody"
                           " dynamics, compliant smooth sphere-half-space contact, mirror"
                           " periodicity",
            "grid": args.intervals, "cost": "squared_torque",
            "threads": args.threads or f"default ({os.cpu_count()} cores)",
            "start": "kinematic guess" if args.start == "guess" else "DMOCC plan",
            **info, "notes": NOTES}
    plan = to_plan(problem, walker, trajectory, args.intervals, meta)
    exchange.write_plan(plan_path, plan)
    print(json.dumps(meta))
    return 0


if __name__ == "__main__":
    sys.exit(main())
