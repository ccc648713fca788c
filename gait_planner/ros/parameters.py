"""The parameters of the node ``gait_planner``: declared with type, range and description,
and checked whenever they are set (at start, from ``--params-file`` or ``-p``, and at run
time).

A value that fails a check is refused with a reason: at start the node does not start (the
reason is the error), at run time the set-parameters call answers successful = False with
the reason and the old value stays. The shipped values are ``config/gait_planner.yaml``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Callable

from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                ParameterType, SetParametersResult)
from rclpy.node import Node

from gait_planner.model.loader import available_scenes
from gait_planner.request import MAX_STEPS

MAX_SOLVE_TIME = 3600.0  # s, the largest time limit a request may ask for (request_ranges)
DEPRECATED_STORE = "plan_library"  # warm_start_store's name until 2026-11-29


def _descriptor(kind: int, description: str, **extra) -> ParameterDescriptor:
    return ParameterDescriptor(type=kind, description=description, **extra)


# name -> (default, descriptor); declared in this order (allowed_output_dirs before
# output_dir and scene_dirs before default_scene, whose checks read them)
DECLARATIONS: dict[str, tuple[Any, ParameterDescriptor]] = {
    "allowed_output_dirs": (["."], _descriptor(
        ParameterType.PARAMETER_STRING_ARRAY,
        "Folders output_dir must be inside (relative ones: to the node's working folder); "
        "fixed at start", read_only=True)),
    "output_dir": ("runs", _descriptor(
        ParameterType.PARAMETER_STRING,
        "Folder of the recordings (MCAP, .rrd), created if missing; must be writable and "
        "inside one of allowed_output_dirs")),
    "scene_dirs": (["scenes"], _descriptor(
        ParameterType.PARAMETER_STRING_ARRAY,
        "Folders of scene files (<name>.yaml) searched before GAIT_PLANNER_SCENE_PATH and "
        "config/scenes, first match wins; relative ones: to the node's working folder; a "
        "missing folder is skipped (logged at start); requests name scenes by bare name; "
        "fixed at start", read_only=True)),
    "robot_package_dirs": ([""], _descriptor(
        ParameterType.PARAMETER_STRING_ARRAY,
        "Folders that resolve the package:// mesh paths of the robot's URDF (relative: to "
        "the node's working folder); empty entries are ignored; fixed at start",
        read_only=True)),
    "robot_mirror_tolerance": (0.05, _descriptor(
        ParameterType.PARAMETER_DOUBLE,
        "How far (a fraction) the robot's right-leg inertial data may differ from the left's "
        "mirror image and be written as it (the half cycle's mirror needs a symmetric robot; "
        "Talos needs 0.06); fixed at start", read_only=True,
        floating_point_range=[FloatingPointRange(from_value=0.0, to_value=0.5)])),
    "robot_description": ("", _descriptor(
        ParameterType.PARAMETER_STRING,
        "A robot's URDF text, as robot_state_publisher takes it: drafted into the scene "
        "'robot_description' (gait_planner.ros.robot_description), as is every URDF "
        "published on /robot_description; empty = only the topic's")),
    "default_scene": ("walker3d", _descriptor(
        ParameterType.PARAMETER_STRING,
        "Scene planned when a request names none (a file <name>.yaml in scene_dirs, "
        "GAIT_PLANNER_SCENE_PATH or config/scenes)")),
    "max_solve_time": (60.0, _descriptor(
        ParameterType.PARAMETER_DOUBLE,
        "Time limit of a solve in s when a request gives <= 0; must be > 0",
        floating_point_range=[FloatingPointRange(from_value=0.0, to_value=MAX_SOLVE_TIME)])),
    "compile_derivatives": (True, _descriptor(
        ParameterType.PARAMETER_BOOL,
        "Evaluate derivatives with per-node elements compiled to C (cached; `make prepare` "
        "and prepare_scenes compile the shipped scenes; a problem not yet compiled is "
        "compiled for the request that needs it)")),
    "prepare_on_start": (True, _descriptor(
        ParameterType.PARAMETER_BOOL,
        "Build the default scene's problem and load the modules that certify and record a "
        "plan at start, before the service and the action are offered, so that the first "
        "request pays no build (walker3d: about 1 s from the compiled cache), then prepare "
        "prepare_scenes in the background",
        read_only=True)),
    "prepare_scenes": (["walker3d", "walker2d", "compass"], _descriptor(
        ParameterType.PARAMETER_STRING_ARRAY,
        "Scenes prepared in full in the background when prepare_on_start is true (every "
        "ground form and gait compiled, the default, the warm-start anchors, the start from "
        "standing and the stop planned: "
        "`gait-planner prepare` in a child process, gait_planner/ros/preparation.py), each "
        "that the cache does not mark prepared; the service /gait_planner/preparation "
        "answers what is ready; empty entries are ignored; fixed at start", read_only=True)),
    "warm_start_store": (True, _descriptor(
        ParameterType.PARAMETER_BOOL,
        "Warm-start from the optima of earlier processes (the warm-start store in the cache "
        "folder, gait_planner/ocp/warm_starts.py; `make prepare` plans the shipped scenes' "
        "default requests, warm-start anchors, starts from standing and stops into it; a "
        "request on another ground or at "
        "another pace is continued from the nearest along a path of parameters) and add this "
        "node's optima to it; a request with cold_start ignores it", read_only=True)),
    DEPRECATED_STORE: (True, _descriptor(
        ParameterType.PARAMETER_BOOL,
        "Deprecated name of warm_start_store (false turns the store off too, with a "
        "warning)", read_only=True)),
    "gait_library": ("", _descriptor(
        ParameterType.PARAMETER_STRING,
        "A gait library's folder (gait-planner library build; empty: none): a request of "
        "its scene, gait and settings inside its grid starts from the interpolation of the "
        "plans around it (gait_planner/gaitlib/serve.py); others are planned as usual, and "
        "the answer's message says which", read_only=True)),
    "feedback_every": (1, _descriptor(
        ParameterType.PARAMETER_INTEGER,
        "Action feedback every this many IPOPT iterations (and at every phase change)",
        integer_range=[IntegerRange(from_value=1, to_value=1000, step=1)])),
    "walk_steps": (0, _descriptor(
        ParameterType.PARAMETER_INTEGER,
        "Half cycles to walk each plan in MuJoCo after it is recorded and published "
        "(gait_planner.walk, config/walk.yaml; about 1 s of computing per half cycle), "
        f"0..{MAX_STEPS}; 0 = no walk. The result's walk_* fields say how it went",
        integer_range=[IntegerRange(from_value=0, to_value=MAX_STEPS, step=1)])),
}


def check_output_dir(value: str, allowed: list[str]) -> str | None:
    """Why `value` cannot be the output folder (None if it can): it must resolve inside one
    of the `allowed` folders, and it or its nearest existing parent must be a writable
    folder (a missing folder is created at the first plan)."""
    if not value:
        return "output_dir must name a folder"
    folder = Path(value).expanduser().resolve()
    roots = [Path(root).expanduser().resolve() for root in allowed]
    if not any(folder == root or root in folder.parents for root in roots):
        return (f"output_dir {value!r} ({folder}) is outside the allowed folders "
                f"{[str(root) for root in roots]} (parameter allowed_output_dirs, set at start)")
    existing = next(p for p in (folder, *folder.parents) if p.exists())
    if not existing.is_dir():
        return f"output_dir {value!r}: {existing} is not a folder"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"output_dir {value!r}: {existing} is not writable by this process"
    return None


def _check_scene(value: str, folders: list[str]) -> str | None:
    scenes = available_scenes(folders)
    return None if value in scenes else (
        f"default_scene {value!r} is not a known scene; available: {', '.join(scenes)} "
        f"(files <name>.yaml in scene_dirs {folders}, GAIT_PLANNER_SCENE_PATH or "
        "config/scenes)")


def check_scene_dirs(value: list[str]) -> str | None:
    """Why `value` cannot be the scene folders (None if it can): every entry names a path,
    and an existing one is a folder (a missing one is skipped)."""
    for entry in value:
        if not entry.strip():
            return f"scene_dirs entries must name folders, got {entry!r} in {list(value)}"
        path = Path(entry).expanduser()
        if path.exists() and not path.is_dir():
            return f"scene_dirs entry {entry!r} ({path.resolve()}) is not a folder"
    return None


def check_gait_library(value: str) -> str | None:
    """Why `value` cannot be the gait library's folder (None if it can: empty, or a folder
    with a library's manifest)."""
    from gait_planner.gaitlib.index import LibraryError, read_manifest

    if not value:
        return None
    try:
        read_manifest(Path(value).expanduser())
    except LibraryError as err:
        return f"gait_library: {err}"
    return None


def _check_solve_time(value: float) -> str | None:
    return None if 0.0 < value <= MAX_SOLVE_TIME else (
        f"max_solve_time must be > 0 and <= {MAX_SOLVE_TIME:g} s, got {value}")


def declare(node: Node) -> None:
    """Declare the parameters of `DECLARATIONS` on `node`, checked by `validator` from
    now on (also the values given at start: a refused one raises, the node does not start)."""
    node.add_on_set_parameters_callback(validator(node))
    for name, (default, descriptor) in DECLARATIONS.items():
        node.declare_parameter(name, default, descriptor)


def validator(node: Node) -> Callable[[list], SetParametersResult]:
    """The set-parameters callback of `node`: refuses a value with the reason."""
    checks: dict[str, Callable[[Any], str | None]] = {
        "default_scene": lambda value: _check_scene(
            value, list(node.get_parameter("scene_dirs").value)),
        "scene_dirs": check_scene_dirs,
        "max_solve_time": _check_solve_time,
        "output_dir": lambda value: check_output_dir(
            value, list(node.get_parameter("allowed_output_dirs").value)),
        "gait_library": check_gait_library,
        "allowed_output_dirs": lambda value: None if len(value) else (
            "allowed_output_dirs must name at least one folder"),
    }

    def on_set(parameters: list) -> SetParametersResult:
        for parameter in parameters:
            check = checks.get(parameter.name)
            reason = check(parameter.value) if check else None
            if reason:
                return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    return on_set
