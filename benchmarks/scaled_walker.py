"""walker3d scaled to another body: the human counterpart of a robot's plan (issue #37).

`scaled_walker3d(leg, mass)` is walker3d (config/scenes/walker3d.yaml) with every length
times s = leg / 0.897 m (walker3d's leg, hip to sole) and every mass times m = mass /
walker3d's total mass, inertias times m s^2; the gait scaled as the URDF importer scales
a robot's (`model.urdf_import`: equal Froude number): step length, swing clearance and the
step-length bounds times s, the base time step and the clearance ramp times sqrt(s),
speeds (strike speed, speed limit) times sqrt(s), joint speeds (deg/s) over sqrt(s); the
twist regularisation's weights (units of the cost) by the energy scale m s (kinetic energy)
and its square (torque squared). Angles (joint ranges, torso lean) and the scaling bounds
(sigma's, dimensionless) keep their values. The other gaits (`gaits:`) and the warm-start
anchors (`gait-planner prepare`'s, not a cold plan's concern) are left out. The variant is
built from the scaled YAML document by the loader (`scene_from_text`), so it is checked as
any scene is; an option this module does not know is refused rather than left unscaled.
"""

from __future__ import annotations

import copy
import math

import yaml

from gait_planner.model.loader import scene_dirs, scene_from_text
from gait_planner.model.scene import Scene
from gait_planner.model.urdf_import import WALKER3D_LEG

LENGTH_OPTIONS = ("swing_clearance", "step_length_bounds")
TIME_OPTIONS = ("swing_clearance_ramp",)
SPEED_OPTIONS = ("strike_speed_max", "speed_max")
RATE_OPTIONS = ("joint_speed_max",)
KEPT_OPTIONS = ("torso_lean_max", "joint_limits", "stairs_down_scaling_bounds",
                "speed_scaling_bounds")


def walker3d_document() -> dict:
    path = next(d / "walker3d.yaml" for d in scene_dirs() if (d / "walker3d.yaml").exists())
    return yaml.safe_load(path.read_text())


def _times(value, factor: float):
    return [v * factor for v in value] if isinstance(value, list) else value * factor


def scaled_document(leg: float, mass: float) -> dict:
    """walker3d's YAML document scaled to `leg` (m, hip to sole) and `mass` (kg)."""
    doc = copy.deepcopy(walker3d_document())
    s = leg / WALKER3D_LEG
    m = mass / sum(b["mass"] for b in doc["bodies"])
    root = math.sqrt(s)
    doc["name"] = f"walker3d_scaled_{leg:.4f}m_{mass:.2f}kg".replace(".", "_")
    doc["description"] = (f"walker3d scaled to a leg of {leg:.4f} m (x{s:.4f}) and "
                          f"{mass:.3f} kg (masses x{m:.4f}), benchmarks/scaled_walker.py")
    doc.pop("gaits", None)
    for body in doc["bodies"]:
        body["mass"] *= m
        body["inertia"] = _times(body["inertia"], m * s * s)
        if "length" in body:
            body["length"] *= s
        body["points"] = {k: _times(v, s) for k, v in body["points"].items()}
    doc["initial_pose"]["root_position"] = _times(doc["initial_pose"]["root_position"], s)
    gait = doc["gait"]
    gait["step_length"] *= s
    gait["base_time_step"] *= root
    options = gait["options"]
    options.pop("warm_start_anchors", None)
    for key, value in options.items():
        if key in LENGTH_OPTIONS:
            options[key] = _times(value, s)
        elif key in TIME_OPTIONS or key in SPEED_OPTIONS:
            options[key] = _times(value, root)
        elif key in RATE_OPTIONS:
            options[key] = _times(value, 1 / root)
        elif key == "twist_regularisation":
            energy = m * s
            options[key] = {"kinetic_energy": value["kinetic_energy"] * energy,
                            "torque_squared": value["torque_squared"] * energy ** 2}
        elif key not in KEPT_OPTIONS:
            raise ValueError(f"walker3d's option {key!r} has no scaling rule in "
                             f"benchmarks/scaled_walker.py")
    return doc


def scaled_walker3d(leg: float, mass: float) -> Scene:
    """The scaled walker3d as a Scene (module docstring)."""
    doc = scaled_document(leg, mass)
    return scene_from_text(yaml.safe_dump(doc, sort_keys=False), f"{doc['name']}.yaml")
