"""The plan a walk follows: a recorded half cycle joined with its mirror images.

`Reference.from_recording(rec, steps)` rebuilds the recording's scene from its attached
scene file and joins `steps` half cycles as `gait_planner.ocp.walk_on` does (half cycle k is
the plan mirrored k times and shifted k step lengths): director coordinates through
`configuration_mirror`, joint angles from them, and joint rates and efforts (conjugate to
the angles, `gait_planner.io.messages`) through the signed permutation the mirror applies
to the angles. `at(t)` interpolates linearly between nodes.

A recording of K > 1 half cycles (`plan --steps K`: metadata ``steps`` = K and
``half_cycle_nodes`` = H, K (H - 2) + 2 nodes, made by `walk_on` the same way) is joined
from its first half cycle, so that any number of steps can be walked; its recorded half
cycles are those mirror images (`verify.joined` checks them), and the walked reference
equals the recorded nodes.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gait_planner.io.mcap_reader import RecordedPlan
from gait_planner.model.angles import angle_names, joint_angles
from gait_planner.model.loader import scene_from_text
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.mirror import configuration_mirror, contact_partners
from gait_planner.verify.joined import half_cycle
from gait_planner.walk.mujoco_model import recorded_ground

__all__ = ["Reference", "angular_velocity", "root_rates_after", "scene_of"]


def scene_of(rec: RecordedPlan) -> Scene:
    """The planner's scene from the recording's attached scene file."""
    name = f"{rec.metadata.get('scene', '')}.yaml"
    return scene_from_text(rec.scene_text, name)


def planned_joints(rec: RecordedPlan) -> RecordedPlan:
    """The recording with only the planned joints in its trajectory: a scene drafted from a
    URDF publishes the locked joints after them (held; the walk welds them)."""
    names = list(angle_names(scene_of(rec)))
    if list(rec.joint_names) == names:
        return rec
    missing = [n for n in names if n not in rec.joint_names]
    if missing:
        raise ValueError(f"{rec.path}: the JointTrajectory lacks the planned joints {missing}")
    keep = [list(rec.joint_names).index(n) for n in names]
    return dataclasses.replace(rec, joint_names=tuple(names), **{
        key: np.asarray(getattr(rec, key))[:, keep]
        for key in ("positions", "velocities", "accelerations", "effort", "joint_state_position",
                    "joint_state_velocity", "joint_state_effort")
        if np.asarray(getattr(rec, key)).shape[1:] == (len(rec.joint_names),)})


def _first_half_cycle(rec: RecordedPlan) -> RecordedPlan:
    """The recording itself if it holds one half cycle, else its first (module docstring);
    ValueError naming the file if its node count is not that of its metadata."""
    steps = int(rec.metadata.get("steps", 1))
    if steps == 1:
        return rec
    H = int(rec.metadata.get("half_cycle_nodes", 0))
    if H < 3 or rec.n_nodes != steps * (H - 2) + 2:
        raise ValueError(f"{rec.path}: {rec.n_nodes} nodes are not {steps} joined half cycles "
                         f"(metadata steps) of half_cycle_nodes = "
                         f"{rec.metadata.get('half_cycle_nodes')!r}: K (H - 2) + 2 nodes")
    return half_cycle(rec, H)


def angular_velocity(D: np.ndarray, D_dot: np.ndarray) -> np.ndarray:
    """Angular velocity (world) of a rotation D with rate D_dot: the axial vector of
    D_dot D^T (antisymmetrised)."""
    W = D_dot @ D.T
    return 0.5 * np.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]])


def root_rates_after(scene: Scene, q: np.ndarray, times: np.ndarray, n: int = 0
                     ) -> tuple[np.ndarray, np.ndarray]:
    """The root body's centre-of-mass velocity and angular velocity (world) just after node
    n: the forward differences of nodes n and n + 1 (at a strike, the rates after the
    impact)."""
    i = scene.body_index(scene.root.body)
    h = float(times[n + 1] - times[n])
    D, D1 = (q[m, 12 * i + 3:12 * i + 12].reshape(3, 3).T for m in (n, n + 1))
    return ((q[n + 1, 12 * i:12 * i + 3] - q[n, 12 * i:12 * i + 3]) / h,
            angular_velocity(D, (D1 - D) / h))


def _angle_mirror(angles: np.ndarray, mirrored: np.ndarray, names) -> np.ndarray:
    """P (na, na), mirrored = angles @ P.T: each mirrored column is +- one plan column."""
    na = angles.shape[1]
    P = np.zeros((na, na))
    for i in range(na):
        errors = [(np.abs(mirrored[:, i] - s * angles[:, j]).max(), j, s)
                  for j in range(na) for s in (1.0, -1.0)]
        err, j, s = min(errors)
        if err > 1e-6:
            raise ValueError(f"the mirror image of joint angle {names[i]!r} is no joint angle "
                             f"of the plan (closest {names[j]!r}, off by {err:.3g} rad)")
        P[i, j] = s
    return P


@dataclass(frozen=True)
class Reference:
    """`steps` joined half cycles: times (M,), q (M, 12 nb), angles/rates/efforts (M, na),
    active contacts per node, the half cycle's duration and node count."""

    scene: Scene
    steps: int
    times: np.ndarray
    q: np.ndarray
    angles: np.ndarray
    rates: np.ndarray
    efforts: np.ndarray
    active: tuple[tuple[str, ...], ...]
    period: float
    step_length: float
    root_rate0: tuple[np.ndarray, np.ndarray]  # root COM velocity, angular velocity (world) at t=0
    normal: np.ndarray  # (3,) the ground's unit normal (e_z on level ground and stairs)

    @classmethod
    def from_recording(cls, rec: RecordedPlan, steps: int) -> "Reference":
        ground = recorded_ground(rec)
        rec = _first_half_cycle(rec)
        scene = scene_of(rec)
        N = rec.n_nodes - 1
        s = float(rec.metadata["step_length"])
        A, shift, lift = configuration_mirror(Multibody.of(scene), ground)
        partner = contact_partners(scene)
        angles0 = joint_angles(scene, rec.q)
        if np.abs(angles0 - rec.positions).max() > 1e-6:
            raise ValueError(f"{rec.path}: the recorded joint positions are not the angles of "
                             f"the recorded configurations of scene {scene.name!r}")
        P = _angle_mirror(angles0, joint_angles(scene, rec.q @ A.T + s * shift + lift),
                          rec.joint_names)
        period = float(rec.times[N - 1] - rec.times[0])
        parts = {k: [] for k in ("t", "q", "r", "e", "a")}
        q_k, r_k, e_k, a_k = rec.q, rec.velocities, rec.effort, rec.active_contacts
        for k in range(steps):
            keep = slice(0, N - 1) if k < steps - 1 else slice(0, N + 1)
            parts["t"].append(rec.times[keep] + k * period)
            parts["q"].append(q_k[keep])
            parts["r"].append(r_k[keep])
            parts["e"].append(e_k[keep])
            parts["a"].extend(a_k[keep])
            q_k, r_k, e_k = q_k @ A.T + s * shift + lift, r_k @ P.T, e_k @ P.T
            a_k = tuple(tuple(partner[c] for c in a) for a in a_k)
        q = np.vstack(parts["q"])
        # the root's rates at node 0: the mirror of the central difference at node N-1
        i = scene.body_index(scene.root.body)
        dt = rec.times[N] - rec.times[N - 2]
        v = (rec.q[N, 12 * i:12 * i + 3] - rec.q[N - 2, 12 * i:12 * i + 3]) / dt
        D = rec.q[N - 1, 12 * i + 3:12 * i + 12].reshape(3, 3).T
        Ddot = (rec.q[N, 12 * i + 3:12 * i + 12] - rec.q[N - 2, 12 * i + 3:12 * i + 12]) / dt
        w = angular_velocity(D, Ddot.reshape(3, 3).T)
        flip = np.array([1.0, -1.0, 1.0])
        return cls(scene, steps, np.concatenate(parts["t"]), q, joint_angles(scene, q),
                   np.vstack(parts["r"]), np.vstack(parts["e"]), tuple(parts["a"]), period, s,
                   (v * flip, -w * flip), ground.normal)

    @classmethod
    def from_result(cls, result) -> "Reference":
        """A plan as it is (a transition, a stop: `gait_planner.transitions`), not joined:
        its nodes, the planned joints' angles, rates and efforts (those its JointTrajectory
        carries, `io.messages.node_efforts`), its active contacts; period: its duration;
        the root's rates at node 0 its first difference."""
        from gait_planner.io.messages import node_efforts

        scene, q, times = result.scene, np.asarray(result.q, float), np.asarray(result.times)
        return cls(scene, 1, times - times[0], q, np.asarray(result.joint_angles, float),
                   np.asarray(result.joint_velocities, float), node_efforts(result),
                   tuple(result.active_contacts), float(times[-1] - times[0]),
                   float(result.step_length), root_rates_after(scene, q, times),
                   result.ground.normal)

    @classmethod
    def as_recorded(cls, rec: RecordedPlan) -> "Reference":
        """A recorded plan as it is (a transition, a stop, as the node records it), not
        joined: its nodes, the planned joints of its trajectory (`planned_joints`), its
        active contacts; period: its duration; the root's rates at node 0 its first
        difference."""
        rec = planned_joints(rec)
        scene, ground = scene_of(rec), recorded_ground(rec)
        q, times = np.asarray(rec.q, float), np.asarray(rec.times, float)
        return cls(scene, 1, times - times[0], q, np.asarray(rec.positions, float),
                   np.asarray(rec.velocities, float), np.asarray(rec.effort, float),
                   tuple(rec.active_contacts), float(times[-1] - times[0]),
                   float(rec.metadata["step_length"]), root_rates_after(scene, q, times),
                   ground.normal)

    def _node_weight(self, t: float) -> tuple[int, float]:
        """(n, a): t lies a of the way from node n to node n + 1 (clipped to the ends)."""
        # min / max, not np.clip: the same numbers, and a walk calls this ~10 times a step
        n = min(max(int(np.searchsorted(self.times, t, side="right")) - 1, 0), len(self.times) - 2)
        a = float((t - self.times[n]) / (self.times[n + 1] - self.times[n]))
        return n, min(max(a, 0.0), 1.0)

    def q_at(self, t: float) -> np.ndarray:
        """The configuration (12 nb,) interpolated at t."""
        n, a = self._node_weight(t)
        return (1 - a) * self.q[n] + a * self.q[n + 1]

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[str, ...]]:
        """Angles, rates, efforts interpolated at time t, and the contacts held there."""
        n, a = self._node_weight(t)
        mix = lambda x: (1 - a) * x[n] + a * x[n + 1]  # noqa: E731
        return mix(self.angles), mix(self.rates), mix(self.efforts), self.active[n]

    def root_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Root COM position and director matrix D (columns d1 d2 d3) interpolated at t."""
        i = self.scene.body_index(self.scene.root.body)
        row = self.q_at(t)
        return row[12 * i:12 * i + 3], row[12 * i + 3:12 * i + 12].reshape(3, 3).T

    def com_at(self, t: float) -> np.ndarray:
        """The whole body's centre of mass (3,) m, world, interpolated at t."""
        masses = np.array([b.mass for b in self.scene.bodies])
        phi = self.q_at(t).reshape(-1, 12)[:, :3]
        return masses @ phi / masses.sum()

    def swing_windows(self, legs: list[set[str]]) -> list[tuple[float, float, int]]:
        """(lift-off time s, strike time s, leg) of every swing of the legs (each a set of
        contact names): the spans between nodes where none of the leg's contacts is held,
        from the node that releases the last to the node that strikes the first."""
        out = []
        for leg, contacts in enumerate(legs):
            free = [not (contacts & set(a)) for a in self.active[:-1]]
            n = 0
            while n < len(free):
                if free[n]:
                    m = n
                    while m < len(free) and free[m]:
                        m += 1
                    out.append((float(self.times[n]), float(self.times[m]), leg))
                    n = m
                n += 1
        return out

    def root_rate_at(self, t: float, h: float) -> np.ndarray:
        """The root's angular velocity (world) at t (`rate_at` over +-h)."""
        D_dot = self.rate_at(lambda s: self.root_at(s)[1], t, h)
        return angular_velocity(self.root_at(t)[1], D_dot)

    def root_velocity_at(self, t: float, h: float) -> np.ndarray:
        """The root's centre-of-mass velocity (3,) m/s, world, at t (`rate_at` over +-h)."""
        return self.rate_at(lambda s: self.root_at(s)[0], t, h)

    def com_velocity_at(self, t: float, h: float) -> np.ndarray:
        """The whole body's centre-of-mass velocity (3,) m/s, world, at t (`rate_at` over
        +-h)."""
        return self.rate_at(self.com_at, t, h)

    def rate_at(self, f: Callable[[float], np.ndarray], t: float, h: float) -> np.ndarray:
        """The rate of a planned quantity f at t (s): (f(t + h) - f(t - h)) / 2 h, one-sided
        where t -+ h leaves the plan's span. The interpolated plan is constant beyond its
        ends, so the central difference at t = 0 gave half the speed: the walk's first
        step then asked the torso's loops for a jump of half the walking speed (walker2d's
        default, with contacts at t = 0: 213 N m at a hip for one step, 2026-11-30)."""
        lo, hi = max(t - h, float(self.times[0])), min(t + h, float(self.times[-1]))
        return (f(hi) - f(lo)) / (hi - lo)
