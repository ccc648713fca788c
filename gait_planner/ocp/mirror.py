"""Mirror periodicity (paper section 6, eqs. 7-9): reflection about the plane y = 0.

A body's mirror image lives in its partner body (right <-> left, torso <-> torso):
phi' = S phi, d1' = S d1, d2' = -S d2, d3' = S d3 with S = diag(1, -1, 1), which keeps the
triad right-handed and maps body point (X1, X2, X3) to the partner's (X1, -X2, X3).
A couple m mirrors to -S m; in parent-director components a spherical joint torque
(t1, t2, t3) becomes (-t1, t2, -t3) on the partner joint, a revolute torque about axis n
becomes t * ((-F n) . n_partner) with F = diag(1, -1, 1), negated when the mirror image
swaps the joint's parent and child (the compass hip).
"""

from __future__ import annotations

import numpy as np

from gait_planner.model.ground import LEVEL, Ground
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import JointType, RootType, Scene

_S = np.diag([1.0, -1.0, 1.0])
_F = np.diag([1.0, -1.0, 1.0])


def contact_partners(scene: Scene) -> dict[str, str]:
    """contact name -> the contact at the same point of the mirror-partner body (whose
    mirror image it is; a body without a partner is its own)."""
    mirror = dict(scene.gait.mirror) if scene.gait else {}
    return {c.name: next(d.name for d in scene.contacts
                         if d.body == mirror.get(c.body, c.body) and d.point == c.point)
            for c in scene.contacts}


def configuration_mirror(mb: Multibody, ground: Ground = LEVEL
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, e, c): the next half cycle's configuration of the half cycle's q is
    mirror(q) + s e + c = A q + s e + c for step length s: A (k, k); e (k,) the shift per
    metre of step, 1 at each body's position x and tan(slope) at its z (the ground rises
    along a ramp, `gait_planner.model.ground`); c (k,) the constant lift, step_height at
    each body's z (stairs)."""
    A, along, up = mirror_parts(mb)
    return A, along + ground.rise_per_step * up, ground.step_height * up


def mirror_parts(mb: Multibody) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, x, z): `configuration_mirror`'s A, and the 0/1 masks (k,) of the bodies'
    positions x and z, so that e = x + tan(slope) z and c = step_height z (a compiled
    problem forms them from its ground's parameters, `ocp.elements.Layout`)."""
    gait = mb.scene.gait
    mirror = dict(gait.mirror) if gait else {}
    A = np.zeros((mb.k, mb.k))
    along, up = np.zeros(mb.k), np.zeros(mb.k)
    for name in mb.body_names:
        partner = mirror.get(name, name)
        src, dst = mb.block(name).start, mb.block(partner).start
        signs = (1.0, 1.0, -1.0, 1.0)  # phi, d1, d2, d3
        for j, sign in enumerate(signs):
            A[dst + 3 * j : dst + 3 * j + 3, src + 3 * j : src + 3 * j + 3] = sign * _S
        along[dst], up[dst + 2] = 1.0, 1.0
    return A, along, up


def torque_mirror(mb: Multibody) -> np.ndarray:
    """B (nt, nt) with mirrored torques tau' = B tau (partner joints)."""
    gait = mb.scene.gait
    mirror = dict(gait.mirror) if gait else {}
    by_bodies = {(j.parent, j.child): j for j in mb.scene.joints}
    B = np.zeros((mb.nt, mb.nt))
    for joint in mb.scene.joints:
        parent, child = mirror.get(joint.parent, joint.parent), mirror.get(joint.child, joint.child)
        src = mb.joint_slices[joint.name]
        if (parent, child) in by_bodies:
            partner, sign = by_bodies[(parent, child)], 1.0
        elif (child, parent) in by_bodies and joint.type is JointType.REVOLUTE:
            # the mirror image swaps parent and child (compass hip): the couple on the
            # joint's child changes sign
            partner, sign = by_bodies[(child, parent)], -1.0
        else:
            raise ValueError(f"joint {joint.name!r} has no mirror partner joint")
        dst = mb.joint_slices[partner.name]
        if joint.type is JointType.SPHERICAL:
            B[dst, src] = np.diag([-1.0, 1.0, -1.0])
        else:
            B[dst, src] = sign * float((-_F @ np.array(joint.axis)) @ np.array(partner.axis))
    return B


def increment_mirror(mb: Multibody) -> np.ndarray | None:
    """M (ndof, ndof), a signed permutation, with mirror(F_d(u, q)) = F_d(M u, mirror(q)) for
    the nodal reparametrisation F_d (`Multibody.reparametrise`): the mirror image of a
    turned configuration is the mirrored configuration turned by the mirrored increments.
    The root's translation mirrors like phi, its rotation vector (world components) like a
    couple (-S w); a joint's increments, components in its parent's triad like its
    torque, mirror as the torques do (`torque_mirror`). None when the root body's mirror
    image is another body (the compass: its hip swaps parent and child), where no such M
    exists. Tested on random increments and configurations (test_ocp_mirror.py)."""
    gait = mb.scene.gait
    root = mb.scene.root
    if dict(gait.mirror if gait else {}).get(root.body, root.body) != root.body:
        return None
    if root.type is RootType.FREE:
        root_signs = [1.0, -1.0, 1.0, -1.0, 1.0, -1.0]  # phi like S phi, rotation like -S w
    else:  # planar: (x, z, pitch) lie in the mirror plane's own motion
        root_signs = [1.0] * mb.root_dof
    M = np.zeros((mb.ndof, mb.ndof))
    M[: mb.root_dof, : mb.root_dof] = np.diag(root_signs)
    M[mb.root_dof :, mb.root_dof :] = torque_mirror(mb)
    return M
