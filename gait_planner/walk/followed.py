"""What a walk that re-plans measures and follows (`walk.replan`), and where its plans come
from: the planner in this process (`local_planning`) or another one that answers the same
questions (a test drives the ROS node this way, test/ros/test_replan_node.py).

* `Measured`: the walker's state as a robot publishes it: its joint states and the root
  frame's pose and twist in the world (the root body's centre of mass and directors; a
  drafted robot's base link), `measure(sim, scene)`; `measured_start` turns it into a
  transition's start (`ocp.joint_state.start_of_joint_state`).
* `Followed`: a plan as the walker follows it: its reference (`walk.reference.Reference`),
  nodes, discrete forces and strikes (the nodes where the gait's first phase begins, where
  a re-plan may start), from a `PlanResult` or from a recording of one.
* `Answer`: a planning request's outcome (converged, message, iterations, what to follow).
* A `Planning` is called as ``planning(kind, start, measured, limit, **fields)``: kind
  "start" (start: `standing_start`, or None for the gait's first node), "prepare re-plan"
  (start None: the gait's first node), "prepare stop" (start None), "re-plan" (start and
  measured: the walker's state), "stop" (start: a node of the plan followed, with
  fields["source"] = (that `Followed`, the node's index)); limit: the solver's time limit
  (s) or None; fields: `transitions.plan_transition`'s steps, halves and stop.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Mapping, Protocol

import numpy as np

from gait_planner.model.angles import angle_names
from gait_planner.model.scene import Scene
from gait_planner.ocp.joint_state import start_of_joint_state
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.solve import Planner
from gait_planner.ocp.transition import StartError, StartState, start_of_plan
from gait_planner.result import PlanResult
from gait_planner.transitions import gait_to_join, plan_transition
from gait_planner.walk.reference import Reference

__all__ = ["Answer", "Followed", "Measured", "Planning", "local_planning", "measure",
           "measured_start", "strikes"]


@dataclass(frozen=True)
class Measured:
    """Joint names, positions (rad) and velocities (rad/s); the root frame's position (m),
    orientation (quaternion x, y, z, w), linear and angular velocity (m/s, rad/s; world
    components); the simulated time (s)."""

    names: tuple[str, ...]
    positions: np.ndarray
    velocities: np.ndarray
    root_position: np.ndarray
    root_xyzw: np.ndarray
    root_linear: np.ndarray
    root_angular: np.ndarray
    time: float


def measure(sim, scene: Scene) -> Measured:
    """The state of the walker `sim` (`walk.simulation.Simulation`) as a robot publishes
    it (module docstring)."""
    import mujoco

    model, data, wm = sim.model, sim.data, sim.wm
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    twist = np.zeros(6)
    if scene.robot is None:
        kind, index = mujoco.mjtObj.mjOBJ_SITE, wm.root_site
        position, R = data.site_xpos[index].copy(), data.site_xmat[index].reshape(3, 3)
    else:
        kind, index = mujoco.mjtObj.mjOBJ_BODY, model.body(wm.root).id
        position, R = data.xpos[index].copy(), data.xmat[index].reshape(3, 3)
    mujoco.mj_objectVelocity(model, data, kind, index, twist, 0)
    wxyz = np.zeros(4)
    mujoco.mju_mat2Quat(wxyz, np.ascontiguousarray(R).reshape(-1))
    return Measured(angle_names(scene), data.qpos[wm.qpos].copy(), data.qvel[wm.dof].copy(),
                    position, np.r_[wxyz[1:], wxyz[0]], twist[3:].copy(), twist[:3].copy(),
                    float(data.time))


def measured_start(scene: Scene, m: Measured, origin: str) -> StartState:
    """The transition's start of a measured state (`ocp.joint_state.start_of_joint_state`:
    q its configuration, the momentum M q_dot)."""
    return start_of_joint_state(scene, m.names, m.positions, m.velocities, m.root_position,
                                m.root_xyzw, m.root_linear, m.root_angular, origin)


def strikes(scene: Scene, phases, times, joined: Mapping[str, str] | None = None
            ) -> np.ndarray:
    """Times (s from the plan's start) of the nodes after node 0 at which the gait's first
    phase begins (phase names without their "~k" copy suffix): where a re-plan may start.
    joined: the plan's settings or recording metadata; where they say how its gait's half
    cycles were joined (`ocp.walk_on`'s "half_cycle_nodes", and `ocp.transition.join`'s
    "transition_nodes" after a transition), the first node of each of those half cycles,
    which is recorded with the earlier half cycle's phase name (the name changes one node
    later: walker2d's re-plans and stops began 15 ms after their strikes, 2026-12-07)."""
    first = scene.gait.phases[0].name
    base = [p.split("~")[0] for p in phases]
    t = np.asarray(times, float) - float(times[0])
    nodes = [n for n in range(1, len(base)) if base[n] == first and base[n - 1] != first]
    if joined and "half_cycle_nodes" in joined:
        start = int(joined.get("transition_nodes", 1)) - 1  # the gait's first node
        span = int(joined["half_cycle_nodes"]) - 2  # intervals per half cycle
        nodes = [n - 1 if n - 1 > 0 and n - 1 >= start and (n - 1 - start) % span == 0
                 else n for n in nodes]
    return np.array([t[n] for n in nodes])


@dataclass(frozen=True)
class Followed:
    """A plan as the walker follows it (module docstring): `result` the `PlanResult` or
    `recording` the plan's own (`io.mcap_reader.RecordedPlan`), whichever it came as."""

    scene: Scene
    ref: Reference
    q: np.ndarray
    times: np.ndarray
    generalized_force: np.ndarray
    strikes: np.ndarray
    step_length: float
    gait_duration: float  # s, the half cycle of the gait it joins
    result: PlanResult | None = None
    recording: Any = None

    @classmethod
    def of_result(cls, result: PlanResult) -> "Followed":
        return cls(result.scene, Reference.from_result(result), np.asarray(result.q, float),
                   np.asarray(result.times, float), np.asarray(result.generalized_force),
                   strikes(result.scene, result.phases, result.times, result.settings),
                   float(result.step_length),
                   float(result.settings.get("gait_duration", result.duration)), result)

    @classmethod
    def of_recording(cls, rec) -> "Followed":
        ref = Reference.as_recorded(rec)
        return cls(ref.scene, ref, np.asarray(rec.q, float), np.asarray(rec.times, float),
                   np.asarray(rec.generalized_force),
                   strikes(ref.scene, rec.phases, rec.times, rec.metadata),
                   float(rec.metadata["step_length"]),
                   float(rec.metadata.get("gait_duration", rec.metadata.get("duration"))),
                   recording=rec)


@dataclass(frozen=True)
class Answer:
    """A planning request's outcome: converged, in words, IPOPT's iterations (None: none
    ran), the plan to follow (None unless converged)."""

    success: bool
    message: str
    iterations: int | None
    followed: Followed | None


class Planning(Protocol):
    def __call__(self, kind: str, start: StartState | None, measured: Measured | None,
                 limit: float | None, **fields) -> Answer: ...


def local_planning(planner: Planner, scene: Scene, settings: GaitSettings,
                   plan: Callable[..., PlanResult] = plan_transition) -> Planning:
    """The plans of a walk from `planner` in this process (`plan`:
    `transitions.plan_transition`, or one that wraps it); starts of None that need one are
    the gait's first node (`start_of_plan` of the planner's gait)."""

    def planning(kind: str, start: StartState | None, measured: Measured | None,
                 limit: float | None, **fields) -> Answer:
        fields.pop("source", None)
        if start is None and kind in ("start", "prepare re-plan"):
            gait = gait_to_join(planner, scene, settings)
            if not gait.success:
                return Answer(False, f"the gait: {gait.message}", gait.stats.iterations, None)
            start = start_of_plan(gait)
        try:
            r = plan(planner, scene, settings if limit is None else
                     settings.with_solve(max_solve_time=limit), start, **fields)
        except StartError as err:
            return Answer(False, f"refused: {err}", None, None)
        return Answer(r.success, r.message if not r.success else "converged",
                      r.stats.iterations, Followed.of_result(r) if r.success else None)

    return planning
