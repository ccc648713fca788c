"""Walking on: a planned half cycle joined to its mirror images, K half cycles in one result.

The half cycle spans nodes 0 .. N-1, and nodes N-1, N are the mirror images of nodes 0, 1
shifted by the step length (and up by the ground's rise, `gait_planner.model.ground`;
paper eqs. 7-9). Half cycle k (k = 0 .. K-1) is the plan
mirrored k times (`ocp.mirror`: left and right bodies swapped, lateral components
negated), k step lengths further along x and k half-cycle durations later. Neighbouring
half cycles share their boundary nodes (kept with the earlier half cycle's forces, which
span both neighbouring intervals), so the joined result has K (N - 1) + 2 nodes: K (N - 1)
intervals and, last, nodes N-1, N of the last half cycle. Every node of a half cycle
satisfies the discrete equations with its neighbours, and the neighbours across a join are
exactly the mirrored nodes the periodicity constraints used, so every inner node of the
joined motion satisfies them too: positions, velocities and forces are continuous at the
joins. J and the duration stay those of one half cycle; `settings["steps"]` and
`settings["half_cycle_nodes"]` say how the result was joined.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from gait_planner.model.angles import joint_angles
from gait_planner.model.multibody import Multibody
from gait_planner.ocp.mirror import configuration_mirror, contact_partners, torque_mirror
from gait_planner.ocp.solution import central_rates
from gait_planner.result import PlanResult

_S = np.array([1.0, -1.0, 1.0])


def mirror_nodes(mb: Multibody, q, tau, gen, forces: dict, rolls: dict, active: tuple):
    """The mirror images about y = 0 (no step) of nodes' configurations q (n, k), torques
    tau (n, nt) (partner joints, `torque_mirror`), discrete forces gen (n, k), contact
    forces {contact: (n, 3)} (partner points, y negated), roll moments {body: (n,)}
    (partner bodies, negated) and held contacts (partner points); in that order."""
    A, B = configuration_mirror(mb)[0], torque_mirror(mb)
    partner, mirror = contact_partners(mb.scene), dict(mb.scene.gait.mirror)
    return (q @ A.T, tau @ B.T, gen @ A.T, {partner[c]: f * _S for c, f in forces.items()},
            {mirror.get(b, b): -r for b, r in rolls.items()},
            tuple(tuple(partner[c] for c in a) for a in active))


def walk_on(result: PlanResult, steps: int) -> PlanResult:
    """`result` (one successful half cycle) joined with its mirror images into `steps`
    half cycles (module docstring); steps = 1 returns `result` itself."""
    if steps < 1:
        raise ValueError(f"steps must be at least 1, got {steps}")
    if steps == 1 or not result.success:
        return result
    scene, N, s = result.scene, result.n_nodes - 1, result.step_length
    M = N - 1  # intervals per half cycle
    mb = Multibody.of(scene)
    A, shift, lift = configuration_mirror(mb, result.ground)
    climb = sum(b.mass for b in scene.bodies) * scene.gravity * result.ground.rise(s)  # J

    parts: dict[str, list] = {key: [] for key in ("q", "tau", "gen", "times", "kinetic",
                                                  "potential", "active", "phases")}
    forces = {c: [] for c in result.contact_forces}
    rolls = {b: [] for b in result.roll_moments}
    q_k, tau_k, gen_k = result.q, result.tau, result.generalized_force
    forces_k, rolls_k, active_k = result.contact_forces, result.roll_moments, result.active_contacts
    period = result.times[M] - result.times[0]
    for k in range(steps):
        # half cycle 0 from its node 0, later ones from node 1 (their node 0 is the previous
        # half cycle's node N-1, whose discrete forces span both neighbouring intervals)
        keep = slice(0 if k == 0 else 1, M + 1 if k < steps - 1 else N + 1)
        for key, values in (("q", q_k), ("tau", tau_k), ("gen", gen_k),
                            ("times", result.times + k * period),
                            ("kinetic", result.kinetic_energy),
                            ("potential", result.potential_energy + k * climb),
                            ("active", active_k), ("phases", result.phases)):
            parts[key].append(values[keep])
        for c in forces:
            forces[c].append(forces_k[c][keep])
        for b in rolls:
            rolls[b].append(rolls_k[b][keep])
        # the next half cycle: the mirror image of this one, one step further
        q_k, tau_k, gen_k, forces_k, rolls_k, active_k = mirror_nodes(
            mb, q_k, tau_k, gen_k, forces_k, rolls_k, active_k)
        q_k = q_k + s * shift + lift

    q, times = np.vstack(parts["q"]), np.concatenate(parts["times"])
    h = np.diff(result.times)
    before = A @ (result.q[N - 2] - s * shift - lift)  # as in `ocp.solution.joint_rates`
    velocities, accelerations = central_rates(
        scene, np.vstack([before, q, q_k[2]]),
        np.concatenate([[times[0] - h[N - 2]], times, [times[-1] + h[1]]]))
    return dataclasses.replace(
        result, times=times, q=q, tau=np.vstack(parts["tau"]),
        joint_angles=joint_angles(scene, q), joint_velocities=velocities,
        joint_accelerations=accelerations, phases=tuple(p for part in parts["phases"] for p in part),
        active_contacts=tuple(a for part in parts["active"] for a in part),
        contact_forces={c: np.vstack(f) for c, f in forces.items()},
        roll_moments={b: np.concatenate(r) for b, r in rolls.items()},
        generalized_force=np.vstack(parts["gen"]),
        kinetic_energy=np.concatenate(parts["kinetic"]),
        potential_energy=np.concatenate(parts["potential"]),
        settings=dict(result.settings, steps=str(steps), half_cycle_nodes=str(N + 1)))
