"""Is a recorded plan a motion a real body and a robot can make? Checks beyond the discrete
equations it was solved with (issue: a physical plan), on what the recording publishes.

The ground is the recording's (`gait_planner.verify.ground`: level, a ramp or stairs, from
the metadata); n its normal, a point's height its `RecordedGround.above` (level: z; ramp:
n . p; stairs: z less the height of the tread under the point).

* Per-point friction: every published point force (full contacts included) lies in its
  own Coulomb cone about n, |F - (n . F) n| <= mu n . F, not only each foot's net force.
* Swing clearance: a contact point is at ground height (height < `GROUND_BAND`) only where
  it is held (listed at the node), or at the node where it is released (listed at the node
  before; at node 0, the node before is the previous half cycle's node N-2, mirrored: a
  point foot lifts off at node 0 when its partner struck at the end). Anywhere else it is a swing point sliding along the ground at zero force, which
  a real foot would catch on: a scuff. In 3D, with the metadata's ``foot_half_width`` w,
  the point's two foot edges p -+ w d2 (d2 its body's lateral director) are checked too:
  the foot is as wide as the full contact's roll moment assumes.
* Scuffs against the stairs: on stairs the straight segment between consecutive nodes of
  every point that is not held over the interval (and of its foot edges) must not pass
  through the stairs (below a tread's height where x is over that tread). Its ends are
  judged above (swing clearance) and by the contact checks; between them it can enter the
  stairs only where it crosses an edge: its height there above the higher tread
  (`RecordedGround.edge_clearance`) must not be negative. The lowest such crossing and
  where it is, (point, node n of the segment n -> n + 1), are reported.
* Strike speed: a contact point's mean speed along the ground (the part of its motion
  normal to n removed: horizontal on level ground and stairs) over the interval that ends
  where it is first held again, against the metadata's ``strike_speed_max`` (0 or absent:
  noted only).
* Strike approach: with ``strike_deceleration_max`` a (m/s^2) in the metadata, the same
  speed over the swing's interval j before that one stays below strike_speed_max + a j
  base_time_step.
* Joint speed: the published JointTrajectory velocities stay below `JOINT_SPEED_MAX`, or
  the scene's higher joint_speed_max option, or a joint's own higher joint_speed_limits
  entry (`joint_speed_limits`); the joint nearest its bound is reported.
* Torque smoothness: away from contact switches (a node whose held contacts differ from its
  neighbour's, and the nodes next to it), no joint's published effort zigzags: three
  consecutive first differences alternating in sign, each larger than `ZIGZAG_STEP` of the
  plan's peak effort. The largest second difference away from switches, relative to the
  peak effort, is reported, and relative to its own joint's peak for the joints whose peak
  is at least a fifth of the plan's (a torque loop meets a step of its own joint).

Every number is computed from the recording (numpy only); `check_physical(rec, scene)`
returns a `PhysicalReport` whose `failures` are sentences.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gait_planner.verify.ground import RecordedGround
from gait_planner.verify.mechanics import Mechanics, SceneData

GROUND_BAND = 1e-3  # m: a point lower than this is at ground height
JOINT_SPEED_MAX = 600.0  # deg/s
ZIGZAG_STEP = 0.02  # of the peak effort: first differences smaller than this are noise
STRONG_JOINT = 0.2  # of the peak effort: joints whose roughness is judged by their own peak
FRICTION_TOLERANCE = 1e-9  # relative to max(1 N, |F|)
SOLID_TOLERANCE = 1e-9  # m: a segment this little below a stair edge's corner only touches it


@dataclass(frozen=True)
class PhysicalReport:
    """Measured physical properties of one recording (units in the field comments)."""

    max_point_friction_ratio: float  # max over points |F - (n . F) n| / (mu n . F)
    min_swing_height: float  # m, lowest swing point (or foot edge, 3D) neither held nor released
    scuffs: tuple[tuple[str, int], ...]  # (point, node) at ground height while swinging
    min_edge_clearance: float  # m, lowest crossing of a stair edge (NaN: no stairs; inf: none)
    edge_clearance_at: tuple[str, int] | None  # (point or foot edge, node n of segment n -> n + 1)
    max_strike_speed: float  # m/s, along the ground, over the interval before a strike
    strike_speed_bound: float  # m/s, the metadata's strike_speed_max (0: none)
    max_joint_speed: float  # deg/s, published velocities of `fastest_joint`
    joint_speed_bound: float  # deg/s, its bound (`joint_speed_limits`)
    fastest_joint: str  # the joint nearest its bound (the fastest, with one bound)
    max_torque_second_difference: float  # relative to the peak effort, away from switches
    # (that relative to its joint's own peak, joint, node): joints above STRONG_JOINT of the
    # peak effort, away from switches (`own_peak_roughness`)
    roughest_joint: tuple[float, str, int]
    zigzags: tuple[tuple[str, int], ...]  # (joint angle, node) where the effort zigzags
    switch_nodes: tuple[int, ...]  # nodes whose held contacts differ from the previous node's
    failures: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.failures


def joint_speed_limit(scene: SceneData) -> float:
    """deg/s: `JOINT_SPEED_MAX`, or the recorded scene's option joint_speed_max where it
    declares a higher one (a run's joints turn faster than a walk's)."""
    declared = scene.options.get("joint_speed_max", 0.0)
    return max(JOINT_SPEED_MAX, float(declared) if isinstance(declared, (int, float)) else 0.0)


def joint_speed_limits(scene: SceneData, names) -> np.ndarray:
    """deg/s per published joint of `names`: `joint_speed_limit`, or the joint's own entry of
    the scene's option joint_speed_limits where it is higher (a drafted robot's URDF
    velocity limits)."""
    own = scene.options.get("joint_speed_limits") or {}
    default = joint_speed_limit(scene)
    return np.array([max(default, float(own[n])) if isinstance(own.get(n), (int, float))
                     else default for n in names], dtype=float)


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
    """The checks of the module docstring on a decoded recording (`RecordedPlan`), on the
    ground its metadata names (ValueError if it names none that can be built)."""
    failures: list[str] = []
    mech = Mechanics(scene)
    ground = RecordedGround.of(rec.metadata)
    normal = ground.normal
    q, n_nodes = np.asarray(rec.q, dtype=float), rec.n_nodes
    active = tuple(tuple(a) for a in rec.active_contacts)
    scuffing_fails = scene.options.get("ground_clearance", True) is not False

    ratio, worst = 0.0, None
    for n in range(n_nodes):
        for name, F in zip(rec.contact_names[n], np.asarray(rec.contact_force_vectors[n])):
            fn, tangential = float(normal @ F), float(ground.tangential(F))
            excess = tangential - mu * fn
            r = tangential / (mu * fn) if fn > 0 else (np.inf if tangential > 0 else 0.0)
            if r > ratio:
                ratio = r
            if excess > FRICTION_TOLERANCE * max(1.0, float(np.linalg.norm(F))):
                worst = worst or (name, n, r)
    if worst:
        failures.append(f"the force on {worst[0]} at node {worst[1]} leaves its own friction "
                        f"cone: |F_t| / (mu F_n) = {worst[2]:.3g}")

    # before node 0 comes the previous half cycle's node N-2 mirrored (node N-1 is node 0's
    # image, `gait_planner.ocp.walk_on`): what it held is released at node 0, a lift-off
    halves = int(rec.metadata.get("half_cycle_nodes", n_nodes))  # N + 1
    by_pair = {pair: c for c, pair in scene.contacts.items()}
    released_at_start = {by_pair.get((scene.mirror[scene.contacts[c][0]], scene.contacts[c][1]))
                         for c in active[halves - 3]} if halves >= 3 else set()
    lowest, scuffs = np.inf, []
    crossing, crossing_at = (np.inf if ground.stairs else np.nan), None
    half_width = 0.0 if scene.planar else float(rec.metadata.get("foot_half_width", 0.0))
    for name in scene.contacts:
        labels, edges = _edges(mech, q, name, half_width)  # (n_nodes, e, 3)
        heights = ground.above(edges).min(axis=1)
        for n in range(n_nodes):
            if name in active[n] or (name in active[n - 1] if n > 0 else
                                     name in released_at_start):
                continue
            lowest = min(lowest, float(heights[n]))
            if heights[n] < GROUND_BAND:
                scuffs.append((name, n))
        if not ground.stairs:  # above a plane a segment is lowest at an end: a node
            continue
        for n in range(n_nodes - 1):
            if name in active[n]:  # held over interval n
                continue
            for label, e0, e1 in zip(labels, edges[n], edges[n + 1]):
                clearance = ground.edge_clearance(e0, e1)
                if clearance < crossing:
                    crossing, crossing_at = clearance, (label, n)
    if scuffs and scuffing_fails:
        failures.append(f"swing contact points at ground height without force (scuffing), "
                        f"(point, node): {scuffs[:6]}{' ...' if len(scuffs) > 6 else ''}")
    if crossing < -SOLID_TOLERANCE and scuffing_fails:
        point, n = crossing_at
        failures.append(f"{point} passes {-crossing:.3g} m through the stairs between nodes "
                        f"{n} and {n + 1} (scuffs against the stairs)")

    strike, times = 0.0, np.asarray(rec.times, dtype=float)
    along = np.eye(3) - np.outer(normal, normal)  # drops the motion along n
    bound = float(rec.metadata.get("strike_speed_max", 0.0))
    deceleration = float(rec.metadata.get("strike_deceleration_max", 0.0)) if bound > 0 else 0.0
    approach = []  # failures of the strike approach, after the strike speed's
    for name in scene.contacts:
        C = along @ mech.contact_matrix(name)

        def mean_speed(a: int) -> float:
            """The point's mean speed along the ground from node a to a + 1 (m/s)."""
            return float(np.linalg.norm(C @ (q[a + 1] - q[a]))) / (times[a + 1] - times[a])

        for n in range(1, n_nodes):
            if name not in active[n] or name in active[n - 1]:
                continue
            strike = max(strike, mean_speed(n - 1))
            j = 1
            while deceleration > 0 and n - 1 - j >= 0 and name not in active[n - 1 - j]:
                speed = mean_speed(n - 1 - j)
                allowed = bound + deceleration * j * float(rec.metadata["base_time_step"])
                if speed > allowed * (1 + 1e-6):
                    approach.append(
                        f"{name} moves at {speed:.4g} m/s along the ground {j} intervals "
                        f"before its strike at node {n} (at most {allowed:.4g} m/s: "
                        f"strike_deceleration_max {deceleration:g} m/s^2)")
                j += 1
    if bound > 0 and strike > bound * (1 + 1e-6):
        failures.append(f"a contact point strikes at {strike:.4g} m/s along the ground "
                        f"(strike_speed_max {bound:g} m/s)")
    failures += approach

    speed = np.degrees(np.abs(np.asarray(rec.velocities, dtype=float)))
    limits = joint_speed_limits(scene, rec.joint_names)
    share = speed / limits[: speed.shape[1]] if speed.ndim == 2 else speed
    fastest = np.unravel_index(int(share.argmax()), speed.shape) if speed.size else (0, 0)
    max_speed = float(speed[fastest]) if speed.size else 0.0
    speed_limit = float(limits[fastest[1]]) if speed.size else joint_speed_limit(scene)
    if max_speed > speed_limit:
        failures.append(f"joint {rec.joint_names[fastest[1]]} turns at {max_speed:.0f} deg/s "
                        f"at node {fastest[0]} (limit {speed_limit:.0f} deg/s)")

    switches = switch_nodes(active)
    calm = near_switch(n_nodes, switches)
    second, zigzags = _torque_roughness(np.asarray(rec.effort, dtype=float), calm,
                                        rec.joint_names)
    own = own_peak_roughness(np.asarray(rec.effort, dtype=float), calm, rec.joint_names)
    if zigzags:
        failures.append(f"joint efforts zigzag from node to node away from contact switches, "
                        f"(angle, node): {zigzags[:6]}{' ...' if len(zigzags) > 6 else ''}")
    return PhysicalReport(
        max_point_friction_ratio=ratio, min_swing_height=float(lowest), scuffs=tuple(scuffs),
        min_edge_clearance=float(crossing), edge_clearance_at=crossing_at,
        max_strike_speed=strike, strike_speed_bound=bound,
        max_joint_speed=max_speed, joint_speed_bound=speed_limit, fastest_joint=rec.joint_names[fastest[1]] if speed.size else "",
        max_torque_second_difference=second, roughest_joint=own, zigzags=tuple(zigzags),
        switch_nodes=switches, failures=tuple(failures))


def _edges(mech: Mechanics, q: np.ndarray, name: str, half_width: float
           ) -> tuple[tuple[str, ...], np.ndarray]:
    """(labels, points (N+1, e, 3) m): contact point `name` at every node of q (N+1, k)
    (e = 1), or with half_width w > 0 its foot's two edges p + w d2 (left) and p - w d2
    (right), d2 its body's lateral director."""
    C = mech.contact_matrix(name)
    p = np.array([C @ row for row in q])
    if half_width == 0.0:
        return (name,), p[:, None, :]
    d2 = mech.director(q, mech.scene.contacts[name][0], 1)
    return ((f"{name} left edge", f"{name} right edge"),
            np.stack([p + half_width * d2, p - half_width * d2], axis=1))


def effort_zigzags(effort: np.ndarray, active, names) -> list[tuple[str, int]]:
    """[(angle, node)] where efforts (N+1, na) zigzag away from contact switches (module
    docstring); active: the held contacts of every node, names: the angles'."""
    active = tuple(tuple(a) for a in active)
    return _torque_roughness(np.asarray(effort, dtype=float),
                             near_switch(len(active), switch_nodes(active)), names)[1]


def own_peak_roughness(effort: np.ndarray, switch: np.ndarray, names
                       ) -> tuple[float, str, int]:
    """(largest |second difference| away from switches relative to its joint's own peak,
    that joint, the node) over the joints whose peak is at least `STRONG_JOINT` of the
    plan's peak effort; efforts (N+1, na), switch (N+1,) bool (a switch or next to one)."""
    peaks = np.abs(effort).max(axis=0) if effort.size else np.zeros(0)
    if effort.shape[0] < 4 or not peaks.size or peaks.max() == 0.0:
        return 0.0, "", 0
    second = np.abs(np.diff(effort, 2, axis=0)) * ~switch[1:-1, None]  # at nodes 1..N-1
    strong = peaks >= STRONG_JOINT * peaks.max()
    relative = np.where(strong, second.max(axis=0) / np.where(strong, peaks, 1.0), 0.0)
    j = int(relative.argmax())
    return float(relative[j]), str(names[j]), int(second[:, j].argmax()) + 1


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
