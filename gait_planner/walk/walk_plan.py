"""Walk a recorded plan in MuJoCo and summarise how it went.

`walk(path, steps, scale=1.0)` reads the recording, joins `steps` half cycles
(`walk.reference`), builds the MuJoCo walker (`walk.mujoco_model`), starts it at node 0
(the plan's positions and velocities) and runs the reference controller (`walk.controller`)
with the parameters of config/walk.yaml until the last half cycle ends or the walker falls
(torso centre of mass `height_drop` below the plan's, or its d3 `tilt` from the plan's) or
loses tracking (a joint `joint_error` from the plan) or the simulation diverges (a state
that is not finite). The plan is followed on its own clock,
paced by the walker's progress (`walk.clock`): the plan's time tau, not the simulated time
t, says which node is tracked, where the half cycles end and when the walk is done, and
every comparison with the plan (tracking, falls, drift, placement, touches) is made at tau.
Returns a JSON-ready summary, with the ground touched where the plan has a foot in the air
(`walk.touches`) and the largest slide of a foot on the ground (`walk.slides`).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any, Callable

import numpy as np
import yaml

from gait_planner.walk.clock import PlanClock
from gait_planner.walk.controller import ReferenceController
from gait_planner.walk.model_error import ModelError
from gait_planner.walk.robot_urdf import RobotUrdf
from gait_planner.walk.simulation import (Simulation, foot_half_width, ground_forces,
                                          walk_model)
from gait_planner.walk.slides import Slides
from gait_planner.walk.touches import Touches

__all__ = ["CONFIG", "foot_half_width", "ground_forces", "load_config", "stop_reason", "walk",
           "walk_model"]

CONFIG = Path(__file__).resolve().parents[2] / "config" / "walk.yaml"
TOUCH_SHARE = 0.1  # of the walker's weight: a contact point carrying more is touching


_KEYS = {"simulation": ("time_step", "foot_sphere_radius", "contact_time_constant",
                        "noslip_iterations"),
         "joints": ("kp", "kd"), "torso": ("kp", "kd", "position_kp", "position_kd"),
         "placement": ("kp", "kd", "max_shift", "height_kp", "swing_margin"),
         "clock": ("pace_gain", "rate_min", "rate_max"),
         "stop": ("height_drop", "tilt", "joint_error")}


def load_config(path: str | Path = CONFIG) -> dict[str, Any]:
    """The controller's parameters (config/walk.yaml); ValueError naming the file and the key
    if one is missing or not a finite number >= 0 (time_step and radius > 0)."""
    with open(path, encoding="utf-8") as stream:
        try:
            cfg = yaml.safe_load(stream)
        except yaml.YAMLError as error:
            raise ValueError(f"{path}: not a YAML file: {error}") from None
    for section, keys in _KEYS.items():
        for key in keys:
            value = (cfg.get(section) or {}).get(key) if isinstance(cfg, dict) else None
            positive = key in ("time_step", "foot_sphere_radius", "contact_time_constant")
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value) or value < 0 or (positive and value == 0):
                raise ValueError(f"{path}: {section}.{key} must be a finite number "
                                 f"{'> 0' if positive else '>= 0'}, got {value!r}")
    passes = cfg["simulation"]["noslip_iterations"]
    if passes != int(passes):
        raise ValueError(f"{path}: simulation.noslip_iterations must be a whole number, "
                         f"got {passes!r}")
    low, high = cfg["clock"]["rate_min"], cfg["clock"]["rate_max"]
    if not 0 < low <= 1 <= high:
        raise ValueError(f"{path}: clock.rate_min and clock.rate_max must satisfy 0 < rate_min "
                         f"<= 1 <= rate_max, got {low!r} and {high!r}")
    predict = (cfg.get("delay") or {}).get("predict") if isinstance(cfg, dict) else None
    if not isinstance(predict, bool):
        raise ValueError(f"{path}: delay.predict must be true or false, got {predict!r}")
    scales = cfg.get("self_test_scales")
    if not isinstance(scales, list) or not all(isinstance(x, (int, float)) and 0 <= x < 1
                                               for x in scales):
        raise ValueError(f"{path}: self_test_scales must be a list of numbers in [0, 1), "
                         f"got {scales!r}")
    return cfg


def _read(path: str | Path):
    from gait_planner.io.mcap_reader import read_plan_mcap

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such recording")
    try:
        return read_plan_mcap(path)
    except ValueError:
        raise
    except Exception as error:  # a broken file: mcap's own errors
        raise ValueError(f"{path}: not a readable plan recording (MCAP): "
                         f"{type(error).__name__}: {error}") from None


def _rms(x) -> float:
    x = np.asarray(x, dtype=float)
    return float(np.sqrt(np.mean(x * x))) if x.size else 0.0


def recorded_robot(rec, scene) -> RobotUrdf:
    """The URDF a drafted scene's recording walks on: the recording's /robot_description
    (rec.urdf), the scene's locked joints, and its mesh folders: the scene's own
    (`RobotSource.search_dirs`) and the absolute ones its package:// paths resolved in when
    it was planned (rec.metadata["robot_package_dirs"], `io.mcap_writer.plan_metadata`:
    the recording's scene names its folders relative to a scene file it does not carry)."""
    planned = [d for d in rec.metadata.get("robot_package_dirs", "").split(os.pathsep) if d]
    return RobotUrdf(rec.urdf, scene.robot.search_dirs() + tuple(planned),
                     dict(scene.robot.locked))


def walk(path: str | Path, steps: int = 10, scale: float = 1.0,
         config: dict[str, Any] | None = None, series: bool = False,
         progress: Callable[[int, int], None] | None = None,
         robot: RobotUrdf | None = None,
         model_error: ModelError | None = None) -> dict[str, Any]:
    """The walk of the module docstring; scale multiplies the plan's efforts (the
    self-test); series adds the per-step trace (key "series"); progress(walked, steps) is
    called at every half cycle's end; robot: the robot's own URDF a drafted plan walks on
    (`walk.mujoco_model`); default: for a scene drafted from a URDF (its ``robot:``
    section), the recording's own (`recorded_robot`); model_error: how the simulated
    walker differs from the plan's model (`walk.model_error`: masses, friction, contact
    stiffness, a torque delay, which with config delay.predict the controller predicts
    through, `walk.predictor`; the summary's "model_error" says what, with the mass
    factors drawn)."""
    import mujoco

    from gait_planner.walk.reference import Reference, planned_joints

    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
    cfg = config or load_config()
    rec = planned_joints(_read(path))
    ref = Reference.from_recording(rec, steps)
    scene = ref.scene
    check_feet(scene, rec.path)
    if robot is None and scene.robot is not None:  # drafted: the recording's own URDF
        robot = recorded_robot(rec, scene)
    sim = Simulation.build(rec, scene, cfg, robot, model_error)
    model, data, wm, gains = sim.model, sim.data, sim.wm, sim.gains
    place = cfg["placement"]
    pace = cfg["clock"]
    clock = PlanClock(pace["pace_gain"], pace["rate_min"], pace["rate_max"])
    control = ReferenceController(model, wm, ref, gains, place["max_shift"], scale, clock)
    root_site = wm.root_site
    sim.place(ref)

    h = model.opt.timestep
    touches = Touches(ref.times, ref.active, [c.name for c in scene.contacts],
                      TOUCH_SHARE * sim.weight())
    slides = Slides(touches.names, touches.threshold, ref.normal)
    t_end = steps * ref.period
    errs, ffs, fbs, plans = [], [], [], []
    trace: dict[str, list] = {k: [] for k in ("time", "plan_time", "position", "velocity",
                                              "torso", "torso_ref", "ground_force",
                                              "contact_position")}

    def record(state, t: float) -> None:
        trace["time"].append(state.time)
        trace["plan_time"].append(t)
        trace["position"].append(state.qpos[wm.qpos].copy())
        trace["velocity"].append(state.qvel[wm.dof].copy())
        trace["torso"].append(np.r_[state.site_xpos[root_site], state.site_xmat[root_site]])
        trace["contact_position"].append(state.site_xpos[wm.contact_sites].copy())

    drift, placement, per_half, boundaries, start = [], [], [], 1, 0
    reason = "completed"
    along = walking_direction(ref)
    speed = ref.step_length / ref.period
    stop = cfg["stop"]
    while clock(data.time) < t_end - 0.5 * h:
        step = sim.step(control, clock, ref, touches, slides, record if series else None)
        errs.append(step.error)
        ffs.append(step.ff)
        fbs.append(step.fb)
        plans.append(step.plan_effort)
        if series:
            trace["torso_ref"].append(np.r_[step.phi_ref, step.D_ref.reshape(-1)])
            trace["ground_force"].append(step.forces)
        clock.pace(h, float(along @ (data.subtree_com[control.root] - ref.com_at(step.tau))),
                   speed)
        reason = stop_reason(stop, data, step.com[2], step.phi_ref[2], step.tilt, step.error,
                             rec.joint_names, step.time)
        if reason != "completed":
            break
        tau = clock(data.time)  # of the state after the step
        if tau >= boundaries * ref.period - 0.5 * h:
            mujoco.mj_kinematics(model, data)
            drift.append((data.site_xpos[root_site] - ref.root_at(tau)[0]).tolist())
            placement.append(_placement_error(ref, data, control, tau))
            per_half.append(_rms(np.degrees(errs[start:])))
            start = len(errs)
            if progress is not None:
                progress(boundaries, steps)
            boundaries += 1
    if series:
        extra = {"joint_names": list(rec.joint_names),
                 "contact_names": [c.name for c in scene.contacts], "feedforward": np.array(ffs),
                 "feedback": np.array(fbs), **{k: np.array(v) for k, v in trace.items()}}
    errs_deg = np.degrees(np.array(errs)) if errs else np.zeros((0, len(rec.joint_names)))
    return {
        "recording": str(rec.path), "scene": scene.name, "steps": steps,
        "torque_scale": scale,
        "half_cycles_walked": len(drift), "time_walked_s": round(float(data.time), 4),
        "plan_time_walked_s": round(float(clock(data.time)), 4),
        "stopped": reason,
        "joint_rms_deg": _rms(errs_deg), "joint_max_deg": float(np.abs(errs_deg).max(initial=0)),
        "joint_rms_per_half_cycle_deg": per_half,
        "feedback_share": _rms(fbs) / max(_rms(plans), 1e-12),
        "feedforward_rms_nm": _rms(ffs), "feedback_rms_nm": _rms(fbs), "plan_rms_nm": _rms(plans),
        "torso_drift_m": drift, "foot_placement_error_m": placement,
        "unplanned_touches": touches.summary(),
        "foot_slide": slides.summary(),
        "controller": {"joints": cfg["joints"], "torso": cfg["torso"], "placement": place,
                       "delay": cfg["delay"],
                       "simulation": cfg["simulation"], "foot_half_width": foot_half_width(rec)},
        **sim.model_error_summary(),
        **({"series": extra} if series else {}),
    }


def check_feet(scene, path) -> None:
    """ValueError naming the recording `path` unless its scene has feet with two contact
    points each (heel and forefoot): the walk's controller places feet."""
    if len(scene.contacts) < 2 or len({c.body for c in scene.contacts}) == len(scene.contacts):
        raise ValueError(f"{path}: scene {scene.name!r} has no foot with two contact "
                         f"points (heel and forefoot); walk needs feet")


def walking_direction(ref) -> np.ndarray:
    """(3,) the unit walking direction on the plan's ground: e_x, or up or down a ramp."""
    along = np.array([1.0, 0.0, 0.0]) - ref.normal[0] * ref.normal
    return along / np.linalg.norm(along)


def stop_reason(stop: dict[str, float], data, height: float, planned_height: float,
                tilt: float, error: np.ndarray, joint_names, t: float) -> str:
    """Why a walk stops at simulated time t (s), or "completed" while it goes on, by the
    rules of config/walk.yaml `stop`: a state that is not finite (MuJoCo's `data`), the
    torso's centre of mass `height` (m) height_drop below the plan's, its axis `tilt` deg
    from the plan's, a joint angle `error` (rad, per joint_names) beyond joint_error."""
    worst = int(np.argmax(np.abs(error)))
    if not (np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()):
        return f"diverged: the simulated state is not finite at t = {t:.3f} s"
    if height < planned_height - stop["height_drop"]:
        return (f"fall: torso centre of mass {height:.3f} m high, "
                f"{planned_height - height:.3f} m below the plan at t = {t:.3f} s")
    if tilt > stop["tilt"]:
        return f"fall: torso tilted {tilt:.1f} deg from the plan at t = {t:.3f} s"
    if abs(math.degrees(error[worst])) > stop["joint_error"]:
        return (f"lost tracking: {joint_names[worst]} {math.degrees(error[worst]):+.1f} deg "
                f"from the plan at t = {t:.3f} s")
    return "completed"


def _placement_error(ref, data, control, tau: float) -> float:
    """m: the largest distance of a contact point the plan holds at the node nearest to the
    plan's time tau from where the plan puts it."""
    n = int(np.argmin(np.abs(ref.times - tau)))
    q_n = ref.q[n]
    worst = 0.0
    for c in ref.active[n]:
        worst = max(worst, float(np.linalg.norm(data.site_xpos[control.contact_site[c]]
                                                - control.planned_point(q_n, c))))
    return worst
