"""Transitions: a plan that begins at a given state and joins a periodic gait (issue #62).

A periodic half cycle begins mid-stride with the gait's own velocity; a robot that is
elsewhere cannot start it. A transition is the same DMOCC problem (the discretisation,
contacts, cones, limits and cost of `ocp.transcription`) over the gait's phases with given
ends instead of mirror periodicity (`Transcription` with settings.start_momentum):

* its node 0 is the start's configuration q_0 and its first step comes from the start's
  momentum p_0 by the discrete Legendre transform (`Transcription._start_row`), as DMOC
  imposes initial conditions (paper section 4);
* its nodes N-1 and N are the gait's nodes 0 and 1 one half cycle on (mirrored, a step
  further, `join_targets`), and its last interval is as long as the gait's first, so that
  every node of the joined motion (`join`) satisfies the discrete equations.

A start is a `StartState`: the periodic plan's own node 0 with its discrete momentum
(`start_of_plan`: the transition from it is that plan), or a measured configuration and
velocity (`start_of_velocity`: p_0 = M q_dot, the continuous Legendre transform, first order
in h against the discrete one). `check_start` refuses a start the first phase's contacts
cannot hold, naming the contact or joint and by how much, before anything is built.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.angles import angle_names, configuration, joint_angles
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Phase, Scene
from gait_planner.ocp.contacts import body_contacts
from gait_planner.ocp.mirror import (configuration_mirror, contact_partners, mirror_parts,
                                     torque_mirror)
from gait_planner.ocp.walk_on import mirror_nodes, walk_on
from gait_planner.ocp.settings import GaitSettings, ground_of
from gait_planner.ocp.solution import end_rates
from gait_planner.result import PlanResult

# How far (m) a contact point of the first phase may be from the ground, and how far any
# point may be below it, for a start to be planned.
CONTACT_TOLERANCE = 0.005
# How far (rad) a start's joint angle may lie outside the scene's range.
ANGLE_TOLERANCE = np.radians(1.0)
# Largest residual of the joint constraints (m) of a start's configuration.
CONSTRAINT_TOLERANCE = 1e-6


class StartError(ValueError):
    """A start state the transition cannot plan from; the message names what and by how
    much."""


@dataclass(frozen=True)
class StartState:
    """Where a transition begins: q (k,) director coordinates (m, -) satisfying the joint
    constraints, momentum (k,) N s its discrete momentum p-_0 (director coordinates),
    where it came from, in words, and whether it stands (`standing_start`: the scene's
    start phases come first)."""

    q: np.ndarray
    momentum: np.ndarray
    origin: str
    standing: bool = False


def standing_start(scene: Scene) -> StartState:
    """The scene's standing pose (its `initial_pose`: for the shipped walkers every joint
    at zero, both feet flat on z = 0; for a drafted robot the draft's) at rest, a start of
    the scene's start phases (gait.start: both feet flat first). StartError if the scene
    declares none."""
    if scene.gait is None or not scene.gait.start:
        raise StartError(f"scene {scene.name!r} declares no start from standing (gait.start "
                         f"phases, docs/user-guide.md)")
    q = standing_configuration(scene)
    return StartState(q, np.zeros_like(q), "standing", standing=True)


def standing_configuration(scene: Scene, tolerance: float = 1e-13) -> np.ndarray:
    """q (k,): the scene's standing pose (`initial_pose`) moved the least so that every
    contact point of its first start phase is on the level ground and, in 3D, every body
    with two of them lies flat (n . d2 = 0: the roll row of a full contact,
    `ocp.contacts`), to `tolerance`: Gauss-Newton with least-norm steps on the root's
    position and angles and the joint angles. A drafted robot's pose is its URDF's zero
    pose, whose feet need not be flat (G1's stand rolled by 1.55e-3, which a standing start
    holds through its start phases and the verifier refuses, 2026-12-07); the shipped
    walkers' poses are already (no step). ValueError if no such pose is found near it."""
    pose = scene.initial_pose
    names = scene.gait.start[0].contacts
    points = [scene.contact(name) for name in names]
    mb = Multibody.of(scene)
    flat = [mb.block(c.body).start + 8  # d2_z in q: n . d2 on level ground
            for c in body_contacts(mb, names) if c.full and not c.planar]
    heights = np.array([mb.point_matrix(c.body, c.point)[2] for c in points])
    joints = [(j.name, j.dof) for j in scene.joints]

    def pose_of(p: np.ndarray):
        angles, at = {}, 6
        for name, dof in joints:
            angles[name], at = tuple(p[at : at + dof]), at + dof
        return dataclasses.replace(pose, root_position=tuple(p[:3]),
                                   root_angles=tuple(p[3:6]), joint_angles=angles)

    def residual(p: np.ndarray) -> np.ndarray:
        q = configuration(scene, pose_of(p))
        return np.concatenate([heights @ q, q[flat]])

    p = np.concatenate([pose.root_position, pose.root_angles, *[
        pose.joint_angles.get(name, (0.0,) * dof) for name, dof in joints]]).astype(float)
    free = np.ones(p.size, bool)
    if scene.planar:  # in the plane: x, z and pitch of the root, and the joints
        free[[1, 3, 5]] = False
    for _ in range(20):
        r = residual(p)
        if np.abs(r).max() <= tolerance:
            return configuration(scene, pose_of(p))
        J = np.array([(residual(p + 1e-7 * e) - r) / 1e-7 for e in np.eye(p.size)[free]]).T
        p[free] -= np.linalg.lstsq(J, r, rcond=None)[0]
    raise ValueError(f"scene {scene.name!r}: no standing pose near its initial_pose puts the "
                     f"start phase's contacts on the ground and its feet flat (residual "
                     f"{np.abs(residual(p)).max():.2e})")


def start_of_plan(plan: PlanResult) -> StartState:
    """The first node of a periodic half cycle `plan` with its discrete momentum
    p-_0 = D2 L_d(q_{-1}, q_0, h_{-1}) + h_{-1}/2 B(q_0)^T tau_0, q_{-1} the mirror image of
    node N-2 a step back (paper eqs. 7-9; `ocp.solution.joint_rates`)."""
    mb = Multibody.of(plan.scene)
    A, shift, lift = configuration_mirror(mb, plan.ground)
    N = plan.n_nodes - 1
    h = np.diff(plan.times)
    before = A @ (plan.q[N - 2] - plan.step_length * shift - lift)
    p = DiscreteMechanics(mb).momentum(before, plan.q[0], h[N - 2], plan.tau[0])
    return StartState(plan.q[0].copy(), p, "the periodic plan's first node")


def start_of_velocity(scene: Scene, q: np.ndarray, q_dot: np.ndarray,
                      origin: str) -> StartState:
    """A measured state: configuration q (k,) and its velocity q_dot (k,) (m/s, 1/s), the
    momentum p = M q_dot (the director mass matrix is constant)."""
    mb = Multibody.of(scene)
    return StartState(np.asarray(q, float).copy(), mb.mass_diagonal * np.asarray(q_dot, float),
                      origin)


def turned_start(scene: Scene, start: StartState, lateral: float, rate: float) -> StartState:
    """`start` moved `lateral` m sideways (3D) and turning rigidly at `rate` rad/s about its
    first held contact point (roll in 3D, pitch in the plane) on top of its own motion: a
    start off the gait whose contacts stay on the ground (robustness tests, benchmarks)."""
    mb = Multibody.of(scene)
    q = np.asarray(start.q, float).copy()
    contact = scene.contact(scene.gait.phases[0].contacts[0])
    centre = mb.point_matrix(contact.body, contact.point) @ q
    w = np.array([rate, 0.0, 0.0]) if mb.root_dof == 6 else np.array([0.0, rate, 0.0])
    q_dot = np.zeros_like(q)
    for i in range(mb.nb):
        if mb.root_dof == 6:
            q[12 * i + 1] += lateral
        q_dot[12 * i : 12 * i + 3] = np.cross(w, q[12 * i : 12 * i + 3] - centre)
        for j in range(3):
            d = slice(12 * i + 3 + 3 * j, 12 * i + 6 + 3 * j)
            q_dot[d] = np.cross(w, q[d])
    return StartState(q, start.momentum + mb.mass_diagonal * q_dot,
                      f"{start.origin} {lateral * 100:+.1f} cm sideways, turning {rate:+.3f} rad/s")


def check_start(scene: Scene, settings: GaitSettings, start: StartState) -> None:
    """StartError unless the first phase's contacts (a standing start's: the scene's first
    start phase) can hold `start`: its configuration
    meets the joint constraints, every contact point held in the first phase is within
    CONTACT_TOLERANCE of the ground and none is below it by more, and every joint
    angle lies within its range (ANGLE_TOLERANCE); numbers finite."""
    mb = Multibody.of(scene)
    q = np.asarray(start.q, float)
    if q.shape != (mb.k,) or np.asarray(start.momentum).shape != (mb.k,):
        raise StartError(f"a start of {scene.name} needs {mb.k} director coordinates and "
                         f"momenta, got {q.shape} and {np.asarray(start.momentum).shape}")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(start.momentum))):
        raise StartError("the start state has NaN or infinite entries")
    residual = float(np.abs(np.array(mb.constraints(q))).max(initial=0.0))
    if residual > CONSTRAINT_TOLERANCE:
        raise StartError(f"the start's configuration breaks the joints by {residual:.3g} m "
                         f"(at most {CONSTRAINT_TOLERANCE:g})")
    names = dict(zip(angle_names(scene), joint_angles(scene, q[None, :])[0]))
    for name, lo, hi in settings.joint_limits:
        value = names[name]
        if value < lo - ANGLE_TOLERANCE or value > hi + ANGLE_TOLERANCE:
            raise StartError(f"joint {name} is at {np.degrees(value):.1f} deg, outside its "
                             f"range [{np.degrees(lo):.1f}, {np.degrees(hi):.1f}] deg")
    first = scene.gait.start[0] if start.standing else scene.gait.phases[0]
    held = set(first.contacts)
    ground = ground_of(scene, settings)
    for contact in scene.contacts:
        point = mb.point_matrix(contact.body, contact.point) @ q  # world (3,)
        z = float(point[2] - ground.height(point[0]))
        if contact.name in held and abs(z) > CONTACT_TOLERANCE:
            where = "above" if z > 0 else "below"
            raise StartError(
                f"contact {contact.name} is {abs(z) * 1e3:.1f} mm {where} the ground, where "
                f"the first phase ({first.name}) holds it (at most "
                f"{CONTACT_TOLERANCE * 1e3:g} mm)")
        if z < -CONTACT_TOLERANCE:
            raise StartError(f"contact {contact.name} is {-z * 1e3:.1f} mm below the ground "
                             f"(at most {CONTACT_TOLERANCE * 1e3:g} mm)")


def mirrored_start(scene: Scene, start: StartState) -> StartState:
    """The mirror image of `start` about y = 0 (`ocp.mirror.configuration_mirror`'s A,
    no step): q' = A q, p' = A p (a signed permutation; partner bodies have equal masses
    and inertias, so M A = A M): a start on the other foot as one on the first phase's."""
    A = configuration_mirror(Multibody.of(scene))[0]
    return dataclasses.replace(start, q=A @ start.q, momentum=A @ start.momentum,
                               origin=f"{start.origin}, mirrored")


def mirrored_result(result: PlanResult) -> PlanResult:
    """`result` mirrored about y = 0, every node: configurations, torques (partner
    joints), discrete forces, contact forces (partner points, y negated), roll moments
    (partner bodies, negated) and held contacts (partner points); phase names kept, as
    `ocp.walk_on` keeps them."""
    scene = result.scene
    q, tau, gen, forces, rolls, active = mirror_nodes(
        Multibody.of(scene), result.q, result.tau, result.generalized_force,
        result.contact_forces, result.roll_moments, result.active_contacts)
    velocities, accelerations = end_rates(scene, q, result.times)
    return dataclasses.replace(
        result, q=q, tau=tau, joint_angles=joint_angles(scene, q),
        joint_velocities=velocities, joint_accelerations=accelerations,
        generalized_force=gen, contact_forces=forces, roll_moments=rolls,
        active_contacts=active, settings=dict(result.settings, transition_mirrored="true"))


def stance_offset(scene: Scene, q: np.ndarray, gait: PlanResult) -> float:
    """How far (m) along x the first held contact point of a start's configuration q (k,)
    is from the gait's at its node 0: the gait is joined that much further on."""
    mb = Multibody.of(scene)
    first = scene.gait.phases[0].contacts[0]
    row = mb.contact_rows(first)[0]
    return float(row @ q - row @ gait.q[0])


def ground_repeat(scene: Scene, q: np.ndarray, gait: PlanResult) -> tuple[float, float]:
    """(dx, dz) m: `Ground.repeat_at` of the gait's ground at the first held contact
    point of a start's configuration q (k,). A transition's landing treads
    (`ocp.contacts.landing_treads`), join targets and clearance edges are counted from the
    tread the gait's first node stands on: a start k treads up the stairs (or along a
    ramp) is planned moved back by (dx, dz) and its answer moved forward again
    (`translated`, `translated_result`)."""
    row = Multibody.of(scene).contact_rows(scene.gait.phases[0].contacts[0])[0]
    return gait.ground.repeat_at(float(row @ q))


def translated(scene: Scene, q: np.ndarray, dx: float, dz: float) -> np.ndarray:
    """Configurations q (..., k) with every body moved dx m along x and dz m up."""
    _, along, up = mirror_parts(Multibody.of(scene))
    return q + dx * along + dz * up


def translated_result(result: PlanResult, dx: float, dz: float) -> PlanResult:
    """`result` with every body moved dx m along x and dz m up at every node (its
    potential energy raised by m g dz); velocities, forces and times as they were."""
    scene = result.scene
    weight = sum(b.mass for b in scene.bodies) * scene.gravity  # N
    return dataclasses.replace(result, q=translated(scene, result.q, dx, dz),
                               potential_energy=result.potential_energy + weight * dz)


def join_targets(gait: PlanResult, offset: float, halves: int = 1) -> np.ndarray:
    """(2, k): the gait's nodes 0 and 1 `halves` half cycles on (mirrored that many
    times, a step further each, `ocp.mirror.configuration_mirror`), moved `offset` m along
    x: the transition's nodes N-1 and N."""
    mb = Multibody.of(gait.scene)
    A, shift, lift = configuration_mirror(mb, gait.ground)
    q = gait.q[0:2]
    for _ in range(halves):
        q = q @ A.T + gait.step_length * shift + lift
    return translated(gait.scene, q, offset, 0.0)


def transition_scene(scene: Scene, halves: int, standing: bool = False, stop: bool = False
                     ) -> Scene:
    """`scene` with a gait of `halves` half cycles of its own: copy j (j = 0 ..
    halves-1) of its phases holds the contacts mirrored j times (the partner points for
    odd j), is named "<phase>~<j+1>" from the second copy on and scales with its own
    sigmas (the scene's indices + j n_sigma). `standing`: the scene's start phases
    (gait.start: both feet flat, ...) come first; `stop`: its stop phases (gait.stop,
    declared after an unmirrored half cycle, so mirrored when the last copy is) come last,
    the last of them at rest. Start and stop phases keep their names and have a sigma
    each, after the copies'. StartError if the scene declares no such phases."""
    gait = scene.gait
    for wanted, phases, key, what in ((standing, gait.start, "start", "start from standing"),
                                      (stop, gait.stop, "stop", "stop")):
        if wanted and not phases:
            raise StartError(f"scene {scene.name!r} declares no {what} (gait.{key} phases, "
                             f"docs/user-guide.md)")
    if halves == 1 and not (standing or stop):
        return scene
    partner, n = contact_partners(scene), gait.n_scalings

    def mirrored(contacts, flip):
        return tuple(partner[c] for c in contacts) if flip else contacts

    copies = [Phase(p.name if j == 0 else f"{p.name}~{j + 1}", mirrored(p.contacts, j % 2),
                    p.scaling + j * n, p.intervals)
              for j in range(halves) for p in gait.phases]
    ends = list(gait.start if standing else ()) + list(gait.stop if stop else ())
    own = {p.name: halves * n + i for i, p in enumerate(ends)}
    first = [dataclasses.replace(p, scaling=own[p.name]) for p in gait.start] if standing else []
    last = [Phase(p.name, mirrored(p.contacts, halves % 2 == 0), own[p.name], p.intervals)
            for p in gait.stop] if stop else []
    return dataclasses.replace(scene, gait=dataclasses.replace(
        gait, phases=tuple(first + copies + last)))


def end_intervals(settings: GaitSettings, scene: Scene, standing: bool, stop: bool
                  ) -> tuple[int, int]:
    """(S, P): how many intervals of a transition's grid (`transition_settings`) its start
    phases (0 unless `standing`) and its stop phases (0 unless `stop`) take; scene: the
    gait's scene, which declares them."""
    grid = settings.intervals
    S = sum(grid[: len(scene.gait.start)]) if standing else 0
    P = sum(grid[len(grid) - len(scene.gait.stop):]) if stop else 0
    return S, P


def transition_settings(gait_settings: GaitSettings, gait: PlanResult, walked: PlanResult,
                        start: StartState, halves: int = 1, stop: bool = False
                        ) -> GaitSettings:
    """The settings of the transition of `halves` half cycles (`transition_scene`, with
    the scene's start phases first for a standing start, its stop phases last for a stop)
    from `start` onto `gait` (planned with `gait_settings`): the start phases' intervals,
    then the gait's grid (its intervals, refined or not) repeated, each copy but the last
    one interval short in its last phase (that interval is the next copy's first; a stop
    follows the last copy there), then the stop phases'; the phases' joint ranges mirrored
    with their copies (`ocp.mirror.torque_mirror`: a roll or yaw range changes sign), no
    refinement, no speed row, the start's momentum, the gait's first interval's scaling
    and its torques walked as far (`walked`: the gait joined to at least halves + 1 half
    cycles by `walk_on`), from the first node of the gait's copies on (held before it, at
    the gait's node 0; in a stop held through its stop phases from where they begin), the
    reference of `CostTerms._join_torques`. A stop ends at rest."""
    scene = gait.scene.gait
    one = [int(i) for i in gait.settings["intervals_per_phase"].split(",")]
    begin = [p.intervals for p in scene.start] if start.standing else []
    intervals = list(begin)
    for j in range(halves):
        intervals += one[:-1] + [one[-1] - (j < halves - 1 or stop)]
    end = [p.intervals for p in scene.stop] if stop else []
    intervals += end
    limits = tuple(gait_settings.phase_joint_limits)
    if halves > 1:
        B = torque_mirror(Multibody.of(gait.scene))
        names = angle_names(gait.scene)
        partner = {names[i]: (names[int(np.argmax(np.abs(B[:, i])))],
                              float(B[np.argmax(np.abs(B[:, i])), i])) for i in range(len(names))}

        def mirrored(ranges):
            return tuple((partner[a][0], lo, hi) if partner[a][1] > 0 else
                         (partner[a][0], -hi, -lo) for a, lo, hi in ranges)

        limits += tuple((f"{phase}~{j + 1}", mirrored(ranges) if j % 2 else ranges)
                        for j in range(1, halves) for phase, ranges in limits)
    N, S, P = sum(intervals), sum(begin), sum(end)
    reference = np.vstack([np.repeat(walked.tau[:1], S, axis=0), walked.tau[: N + 1 - S]])
    if stop:
        reference[N - P :] = reference[N - P]
    first = float(np.diff(gait.times)[0] / gait_settings.base_time_step)
    return dataclasses.replace(gait_settings, intervals=tuple(intervals), refinements=0,
                               speed=0.0, step_length=gait.step_length,
                               phase_joint_limits=limits,
                               start_momentum=tuple(float(v) for v in start.momentum),
                               end_scaling=first, end_at_rest=stop,
                               end_torque=tuple(float(v) for v in reference.ravel()))


def join(transition: PlanResult, walked: PlanResult, offset: float, halves: int = 1,
         lead: int = 0) -> PlanResult:
    """The transition (nodes 0..N: `lead` intervals of start phases, then `halves` half
    cycles) followed by `walked`, the gait joined to halves + K half cycles
    (`ocp.walk_on`), from its node N - lead on, moved `offset` m along x: one motion whose
    node N-1 is the transition's (its forces span both neighbouring intervals) and whose
    later nodes are the gait's K half cycles, of the gait's scene; the transition's phases
    keep their names ("<phase>~<j>" for the copies, `transition_scene`), the gait's are
    `walk_on`'s. J and the duration are the transition's; settings["transition_nodes"]
    says where the gait begins."""
    N = transition.n_nodes - 1
    M = N - lead  # the gait's node joined at the transition's node N
    t0 = transition.times[N - 1] - walked.times[M - 1]
    q = np.vstack([transition.q[:N], translated(walked.scene, walked.q[M:], offset, 0.0)])
    times = np.concatenate([transition.times[:N], walked.times[M:] + t0])

    def stack(a, b):
        return np.concatenate([a[:N], b[M:]])

    forces = {c: stack(f, walked.contact_forces[c]) for c, f in transition.contact_forces.items()}
    rolls = {b: stack(r, walked.roll_moments[b]) for b, r in transition.roll_moments.items()}
    velocities, accelerations = end_rates(transition.scene, q, times)
    return dataclasses.replace(
        transition, times=times, q=q, tau=stack(transition.tau, walked.tau),
        joint_angles=joint_angles(transition.scene, q), joint_velocities=velocities,
        joint_accelerations=accelerations,
        scene=walked.scene,
        phases=transition.phases[:N] + walked.phases[M:],
        active_contacts=transition.active_contacts[:N] + walked.active_contacts[M:],
        contact_forces=forces, roll_moments=rolls,
        generalized_force=stack(transition.generalized_force, walked.generalized_force),
        kinetic_energy=stack(transition.kinetic_energy, walked.kinetic_energy),
        potential_energy=stack(transition.potential_energy, walked.potential_energy),
        settings=dict(transition.settings, transition_nodes=str(N),
                      transition_half_cycles=str(halves),
                      steps=str(int(walked.settings.get("steps", "1")) - halves),
                      half_cycle_nodes=walked.settings.get("half_cycle_nodes",
                                                           str(walked.n_nodes))))
