"""The time series of a plan's rerun view: their values, plots, colours and legend names.

`series_values` holds every series as an entity path -> (N+1,) values at the nodes:

* ``plots/joint_angle/<angle>`` (deg), ``plots/joint_torque/<angle>`` (N m, the effort
  convention of `gait_planner.io.messages`: the node torque);
* ``plots/contact_force/<contact>/{x,y,z}`` (N, zero while inactive: each point force is a
  contact multiplier); ``plots/roll_moment/<foot>`` (N m, the full contact's moment about the
  heel-toe line, its sixth multiplier; 3D scenes only);
* ``plots/energy/{kinetic,potential,total}`` (J; potential and total less V at node 0);
* ``plots/angular_momentum/{x,y,z}`` (kg m^2/s): `angular_momentum`, about the whole-body
  centre of mass.

`plot_groups` says which series share a plot: the angles, and the torques, of one joint of
one leg (hip, knee, ankle; right, left; a joint of no side, e.g. compass's hip, alone), ground
forces per foot (heel and forefoot), roll moments, energies, angular momentum components.
The plots show no legend (`gait_planner.viz.rerun_blueprint`): a title names its series and
their colours where there is room (a joint plot's title is short, for narrow plots: joint,
leg R or L and unit, deg for angles and N m for torques), `COLOUR_KEY` says them for all
plots. Each plot also draws the phase boundaries (`phase_boundaries`) as grey vertical
lines, the series ``plots/phase_boundaries/<group key>``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from gait_planner.io.messages import node_efforts
from gait_planner.result import PlanResult

__all__ = ["AXIS_COLORS", "BOUNDARY_COLOR", "COLOUR_KEY", "PlotGroup", "angular_momentum",
           "axis_of", "joint_color", "joint_of", "phase_boundaries", "plot_groups", "poses",
           "series_color", "series_name", "series_values", "side_of", "whole_body_com"]

# Colours of the series: joint angles by their axis (pitch, roll, yaw; a revolute joint's
# angle as a pitch), the same in every joint plot; x, y, z components red, green, blue
# (forefoot forces lighter than heel forces).
_JOINT_PALETTE = ((31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40),
                  (148, 103, 189), (140, 86, 75), (227, 119, 194), (127, 127, 127))
AXIS_COLORS = ((214, 39, 40), (44, 160, 44), (31, 119, 180))
_LIGHT_AXIS_COLORS = ((250, 140, 130), (140, 220, 120), (120, 180, 240))
_ENERGY_COLORS = {"kinetic": (214, 39, 40), "potential": (31, 119, 180), "total": (40, 40, 40)}
BOUNDARY_COLOR = (150, 150, 150)
_PALETTE_NAMES = ("blue", "orange", "green", "red", "purple", "brown", "pink", "grey")
_AXES = ("pitch", "roll", "yaw")
COLOUR_KEY = ("joint angles and torques: pitch blue, roll orange, yaw green (a revolute joint "
              "blue); ground forces and angular momentum: x red, y green, z blue (forefoot "
              "lighter than heel); energy: kinetic red, potential blue, total black (potential "
              "and total less V at t = 0); grey vertical lines: phase boundaries. Hover a line "
              "for its name and value.")


@dataclass(frozen=True)
class PlotGroup:
    """Series (entity paths, no leading slash) shown in one time-series view."""

    key: str
    title: str
    paths: tuple[str, ...]
    boundaries: str = "phase_boundaries"  # the plot's grey vertical lines: plots/<this>/<key>

    @property
    def boundary_path(self) -> str:
        return f"plots/{self.boundaries}/{self.key}"


def side_of(name: str) -> str:
    """"right", "left" or "joints" (no side) of a joint-angle or body name (``_r``/``_l``)."""
    if re.search(r"_r(_|$)", name):
        return "right"
    if re.search(r"_l(_|$)", name):
        return "left"
    return "joints"


def axis_of(name: str) -> str:
    """"pitch", "roll", "yaw" of a spherical joint's angle name (hip_r_roll), else ""."""
    return next((a for a in _AXES if name.endswith(f"_{a}")), "")


def joint_of(name: str) -> str:
    """The joint of a joint-angle name without side and axis: hip_r_roll -> hip."""
    axis = axis_of(name)
    return re.sub(r"_[rl](?=_|$)", "", name[: -len(axis) - 1] if axis else name)


def _feet(result: PlanResult) -> dict[str, list[str]]:
    feet: dict[str, list[str]] = {}
    for contact in result.scene.contacts:
        feet.setdefault(contact.body, []).append(contact.name)
    return feet


def plot_groups(result: PlanResult) -> list[PlotGroup]:
    """The plots of `result`'s time series, in the order of the layout."""
    joints: dict[tuple[str, str], list[str]] = {}
    for name in result.joint_angle_names:
        joints.setdefault((joint_of(name), side_of(name)), []).append(name)
    order = [(j, s) for j in dict.fromkeys(j for j, _ in joints)
             for s in ("right", "left", "joints") if (j, s) in joints]
    groups = [PlotGroup(f"joint_{kind}_{j}_{s}",
                        f"{j}{'' if s == 'joints' else ' ' + s[0].upper()} ({unit})",
                        tuple(f"plots/joint_{kind}/{a}" for a in joints[j, s]))
              for kind, unit in (("angle", "deg"), ("torque", "N m")) for j, s in order]
    feet = _feet(result)
    groups += [PlotGroup(f"contact_force_{body}", f"ground force on {body} (N): x red, y green, "
                         "z blue", tuple(f"plots/contact_force/{c}/{axis}" for c in contacts
                                         for axis in "xyz"))
               for body, contacts in feet.items()]
    groups.append(PlotGroup("energy", "energy (J): kinetic red, potential blue, total black",
                            tuple(f"plots/energy/{e}" for e in ("kinetic", "potential", "total"))))
    groups.append(PlotGroup("angular_momentum",
                            "angular momentum (kg m^2/s): x red, y green, z blue",
                            tuple(f"plots/angular_momentum/{axis}" for axis in "xyz")))
    if not result.scene.planar:
        colours = ", ".join(f"{body} {_PALETTE_NAMES[i % len(_PALETTE_NAMES)]}"
                            for i, body in enumerate(feet))
        groups.append(PlotGroup("roll_moment", f"roll moment (N m): {colours}",
                                tuple(f"plots/roll_moment/{body}" for body in feet)))
    return groups


def joint_color(name: str) -> tuple[int, int, int]:
    """The colour of a joint angle's series (and its torque's) by the angle's axis: pitch
    blue, roll orange, yaw green; a revolute joint's angle as a pitch."""
    axis = axis_of(name)
    return _JOINT_PALETTE[_AXES.index(axis) if axis else 0]


def series_color(result: PlanResult, path: str) -> tuple[int, int, int]:
    """The colour of the series at `path` (a path of `plot_groups`)."""
    parts = path.split("/")
    kind, name = parts[1], parts[2]
    if kind in ("joint_angle", "joint_torque"):
        return joint_color(name)
    if kind == "contact_force":
        axis = "xyz".index(parts[3])
        body = result.scene.contact(name).body
        first = _feet(result)[body][0] == name
        return (AXIS_COLORS if first else _LIGHT_AXIS_COLORS)[axis]
    if kind == "angular_momentum":
        return AXIS_COLORS["xyz".index(name)]
    if kind == "energy":
        return _ENERGY_COLORS[name]
    bodies = list(_feet(result))
    return _JOINT_PALETTE[bodies.index(name) % len(_JOINT_PALETTE)]


def series_name(result: PlanResult, path: str) -> str:
    """The legend entry of the series at `path`: its name without the plot's title, e.g.
    "hip pitch" for plots/joint_angle/hip_r_pitch, "heel z" for .../foot_r_heel/z."""
    parts = path.split("/")
    kind, name = parts[1], parts[2]
    if kind in ("joint_angle", "joint_torque"):
        return re.sub(r"_[rl](_|$)", r"\1", name).replace("_", " ").strip()
    if kind == "contact_force":
        point = result.scene.contact(name).point
        return f"{point} {parts[3]}"
    return name


def poses(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Configurations q (n, 12 nb) -> (n, nb, 3) COMs and (n, nb, 3, 3) director matrices
    D = [d1 d2 d3]."""
    q = np.asarray(q, dtype=float).reshape(len(q), -1, 12)
    return q[:, :, :3], np.transpose(q[:, :, 3:].reshape(len(q), -1, 3, 3), (0, 1, 3, 2))


def whole_body_com(result: PlanResult, phi: np.ndarray) -> np.ndarray:
    """(N+1, 3) whole-body centre of mass from the bodies' COMs phi (N+1, nb, 3)."""
    masses = np.array([b.mass for b in result.scene.bodies])
    return np.einsum("b,nbk->nk", masses, phi) / masses.sum()


def angular_momentum(result: PlanResult) -> np.ndarray:
    """(N+1, 3) angular momentum of the whole body about its centre of mass c, kg m^2/s.

    Per body, in director coordinates, L = m (phi - c) x (phi_dot - c_dot)
    + sum_i E_i d_i x d_i_dot (E_i the Euler-tensor values). Like the kinetic energy of
    `gait_planner.ocp.solution`, it is evaluated per interval, with the interval velocities
    (q_{n+1} - q_n) / h_n and the interval midpoints (q_n + q_{n+1}) / 2, and averaged to
    the nodes (nodes 0 and N take their one interval's value). Each term is then
    a_n x a_{n+1} / h_n; without gravity and ground forces the variational integrator
    conserves this interval value exactly (its discrete momentum map).
    """
    phi, D = poses(result.q)
    c = whole_body_com(result, phi)
    h = np.diff(np.asarray(result.times, dtype=float))
    r = phi - c[:, None, :]
    masses = np.array([b.mass for b in result.scene.bodies])
    euler = np.array([b.euler_tensor for b in result.scene.bodies])  # (nb, 3)
    translation = np.einsum("b,nbk->nk", masses, np.cross(r[:-1], r[1:]))
    rotation = np.einsum("bi,nbki->nk", euler, np.cross(D[:-1], D[1:], axis=2))
    per_interval = (translation + rotation) / h[:, None]
    return np.concatenate([per_interval[:1], 0.5 * (per_interval[:-1] + per_interval[1:]),
                           per_interval[-1:]])


def phase_boundaries(result: PlanResult) -> np.ndarray:
    """Times (from t_0) where a phase starts, after the first, and the half cycle's end."""
    t = np.asarray(result.times, dtype=float) - float(result.times[0])
    phases = list(result.phases)
    starts = [t[n] for n in range(1, result.n_nodes) if phases[n] != phases[n - 1]]
    return np.array(starts + [result.duration])


def series_values(result: PlanResult) -> dict[str, np.ndarray]:
    """Entity path -> (N+1,) values of every series of `plot_groups` (module docstring)."""
    values: dict[str, np.ndarray] = {}
    angles = np.degrees(np.asarray(result.joint_angles, dtype=float))
    torques = node_efforts(result)
    for k, name in enumerate(result.joint_angle_names):
        values[f"plots/joint_angle/{name}"] = angles[:, k]
        values[f"plots/joint_torque/{name}"] = torques[:, k]
    zero = np.zeros((result.n_nodes, 3))
    for contact in result.scene.contacts:
        forces = np.asarray(result.contact_forces.get(contact.name, zero), dtype=float)
        for axis, column in zip("xyz", forces.T):
            values[f"plots/contact_force/{contact.name}/{axis}"] = column
    for body in {c.body: None for c in result.scene.contacts} if not result.scene.planar else ():
        values[f"plots/roll_moment/{body}"] = np.asarray(
            result.roll_moments.get(body, zero[:, 0]), dtype=float)
    kinetic = np.asarray(result.kinetic_energy, dtype=float)
    potential = np.asarray(result.potential_energy, dtype=float)
    potential = potential - potential[0]
    for name, v in (("kinetic", kinetic), ("potential", potential),
                    ("total", kinetic + potential)):
        values[f"plots/energy/{name}"] = v
    for axis, column in zip("xyz", angular_momentum(result).T):
        values[f"plots/angular_momentum/{axis}"] = column
    return values
