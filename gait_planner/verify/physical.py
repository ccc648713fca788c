"""Is a recorded plan a motion a real body and a robot can make? Checks beyond the discrete
equations it was solved with (issue: a physical plan), on what the recording publishes.

* Per-point friction: every published point force (full contacts included) lies in its
  own Coulomb cone, sqrt(F_x^2 + F_y^2) <= mu F_z, not only each foot's net force.
* Swing clearance: a contact point is at ground height (z < `GROUND_BAND`) only where it is
  held (listed at the node), or at the node where it is released (listed at the node
  before). Anywhere else it is a swing point sliding along the ground at zero force, which
  a real foot would catch on: a scuff. In 3D, with the metadata's ``foot_half_width`` w,
  the point's two foot edges z -+ w d2_z (d2 its body's lateral director) are checked too:
  the foot is as wide as the full contact's roll moment assumes.
* Strike speed: a contact point's mean horizontal speed over the interval that ends where
  it is first held again, against the metadata's ``strike_speed_max`` (0 or absent: noted
  only).
* Joint speed: the published JointTrajectory velocities stay below `JOINT_SPEED_MAX`.
* Torque smoothness: away from contact switches (a node whose held contacts differ from its
  neighbour's, and the nodes next to it), no joint's published effort zigzags: three
  consecutive first differences alternating in sign, each larger than `ZIGZAG_STEP` of the
  plan's peak effort. The largest second difference away from switches, relative to the
  peak effort, is reported.

Every number is computed from the recording (numpy only); `check_physical(rec, scene)`
returns a `PhysicalReport` whose `failures` are sentences.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gait_planner.verify.mechanics import Mechanics, SceneData

GROUND_BAND = 1e-3  # m: a point lower than this is at ground height
JOINT_SPEED_MAX = 600.0  # deg/s
ZIGZAG_STEP = 0.02  # of the peak effort: first differences smaller than this are noise
FRICTION_TOLERANCE = 1e-9  # relative to max(1 N, |F|)


@dataclass(frozen=True)
class PhysicalReport:
    """Measured physical properties of one recording (units in the field comments)."""

    max_point_friction_ratio: float  # max over points sqrt(Fx^2 + Fy^2) / (mu Fz)
    min_swing_height: float  # m, lowest swing point (or foot edge, 3D) neither held nor released
    scuffs: tuple[tuple[str, int], ...]  # (point, node) at ground height while swinging
    max_strike_speed: float  # m/s, horizontal, over the interval before a strike
    strike_speed_bound: float  # m/s, the metadata's strike_speed_max (0: none)
    max_joint_speed: float  # deg/s, published velocities
    fastest_joint: str
    max_torque_second_difference: float  # relative to the peak effort, away from switches
    zigzags: tuple[tuple[str, int], ...]  # (joint angle, node) where the effort zigzags
    switch_nodes: tuple[int, ...]  # nodes whose held contacts differ from the previous node's
    failures: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.failures


def switch_nodes(active: tuple[tuple[str, ...], ...]) -> tuple[int, ...]:
    """Nodes n >= 1 whose held contacts differ from those of node n - 1."""
    return tuple(n for n in range(1, len(active)) if set(active[n]) != set(active[n - 1]))


def near_switch(n_nodes: int, switches: tuple[int, ...]) -> np.ndarray:
    """(n_nodes,) bool: a switch node or a neighbour of one."""
    out = np.zeros(n_nodes, dtype=bool)
    for s in switches:
        out[max(s - 1, 0) : s + 2] = True
    return out


def check_physical(rec, scene: SceneData, mu: float) -> PhysicalReport:
    """The checks of the module docstring on a decoded recording (`RecordedPlan`)."""
    failures: list[str] = []
    mech = Mechanics(scene)
    q, n_nodes = np.asarray(rec.q, dtype=float), rec.n_nodes
    active = tuple(tuple(a) for a in rec.active_contacts)

    ratio, worst = 0.0, None
    for n in range(n_nodes):
        for name, F in zip(rec.contact_names[n], np.asarray(rec.contact_force_vectors[n])):
            tangential = float(np.hypot(F[0], F[1]))
            excess = tangential - mu * F[2]
            r = tangential / (mu * F[2]) if F[2] > 0 else (np.inf if tangential > 0 else 0.0)
            if r > ratio:
                ratio = r
            if excess > FRICTION_TOLERANCE * max(1.0, float(np.linalg.norm(F))):
                worst = worst or (name, n, r)
    if worst:
        failures.append(f"the force on {worst[0]} at node {worst[1]} leaves its own friction "
                        f"cone: |F_t| / (mu F_z) = {worst[2]:.3g}")

    lowest, scuffs = np.inf, []
    half_width = 0.0 if scene.planar else float(rec.metadata.get("foot_half_width", 0.0))
    for name in scene.contacts:
        C = mech.contact_matrix(name)
        body = scene.contacts[name][0]
        for n in range(n_nodes):
            if name in active[n] or (n > 0 and name in active[n - 1]):
                continue
            z = float((C @ q[n])[2]) - half_width * abs(float(mech.director(q[n], body, 1)[2]))
            lowest = min(lowest, z)
            if z < GROUND_BAND:
                scuffs.append((name, n))
    if scuffs and scene.options.get("ground_clearance", True) is not False:
        failures.append(f"swing contact points at ground height without force (scuffing), "
                        f"(point, node): {scuffs[:6]}{' ...' if len(scuffs) > 6 else ''}")

    strike, times = 0.0, np.asarray(rec.times, dtype=float)
    for name in scene.contacts:
        C = mech.contact_matrix(name)[:2]
        for n in range(1, n_nodes):
            if name in active[n] and name not in active[n - 1]:
                step = float(np.linalg.norm(C @ (q[n] - q[n - 1])))
                strike = max(strike, step / (times[n] - times[n - 1]))
    bound = float(rec.metadata.get("strike_speed_max", 0.0))
    if bound > 0 and strike > bound * (1 + 1e-6):
        failures.append(f"a contact point strikes at {strike:.4g} m/s horizontally "
                        f"(strike_speed_max {bound:g} m/s)")

    speed = np.degrees(np.abs(np.asarray(rec.velocities, dtype=float)))
    fastest = np.unravel_index(int(speed.argmax()), speed.shape) if speed.size else (0, 0)
    max_speed = float(speed.max()) if speed.size else 0.0
    if max_speed > JOINT_SPEED_MAX:
        failures.append(f"joint {rec.joint_names[fastest[1]]} turns at {max_speed:.0f} deg/s "
                        f"at node {fastest[0]} (limit {JOINT_SPEED_MAX:.0f} deg/s)")

    switches = switch_nodes(active)
    second, zigzags = _torque_roughness(np.asarray(rec.effort, dtype=float),
                                        near_switch(n_nodes, switches), rec.joint_names)
    if zigzags:
        failures.append(f"joint efforts zigzag from node to node away from contact switches, "
                        f"(angle, node): {zigzags[:6]}{' ...' if len(zigzags) > 6 else ''}")
    return PhysicalReport(
        max_point_friction_ratio=ratio, min_swing_height=float(lowest), scuffs=tuple(scuffs),
        max_strike_speed=strike, strike_speed_bound=bound,
        max_joint_speed=max_speed, fastest_joint=rec.joint_names[fastest[1]] if speed.size else "",
        max_torque_second_difference=second, zigzags=tuple(zigzags),
        switch_nodes=switches, failures=tuple(failures))


def effort_zigzags(effort: np.ndarray, active, names) -> list[tuple[str, int]]:
    """[(angle, node)] where efforts (N+1, na) zigzag away from contact switches (module
    docstring); active: the held contacts of every node, names: the angles'."""
    active = tuple(tuple(a) for a in active)
    return _torque_roughness(np.asarray(effort, dtype=float),
                             near_switch(len(active), switch_nodes(active)), names)[1]


def _torque_roughness(effort: np.ndarray, switch: np.ndarray, names) -> tuple[float, list]:
    """(largest |second difference| / peak away from switches, [(angle, node) of zigzags])
    of efforts (N+1, na); a zigzag at node n: d_{n-1}, d_n, d_{n+1} (d_m = e_{m+1} - e_m)
    alternate in sign, each above ZIGZAG_STEP * peak, with nodes n-1 .. n+2 away from
    switches."""
    peak = float(np.abs(effort).max()) if effort.size else 0.0
    if peak == 0.0 or effort.shape[0] < 4:
        return 0.0, []
    d = np.diff(effort, axis=0)  # (N, na)
    second = np.abs(np.diff(d, axis=0)) / peak  # at nodes 1..N-1
    calm = ~switch[1:-1]
    worst = float(second[calm].max()) if calm.any() else 0.0
    zigzags = []
    big = np.abs(d) > ZIGZAG_STEP * peak
    for n in range(1, effort.shape[0] - 2):
        if switch[n - 1 : n + 3].any():
            continue
        for j in range(effort.shape[1]):
            a, b, c = d[n - 1, j], d[n, j], d[n + 1, j]
            if big[n - 1 : n + 2, j].all() and a * b < 0 and b * c < 0:
                zigzags.append((names[j], n))
    return worst, zigzags
