"""Independent check of a recorded gait plan: does the MCAP file hold a valid half cycle?

`verify_recording(path)` reads the recording with `gait_planner.io.mcap_reader` (which shares
no code with the writer), rebuilds the mechanics from the scene file attached to it (plain
YAML, parsed here) and re-derives everything in numpy. It deliberately imports nothing of
`gait_planner.model.multibody`, `gait_planner.dynamics` or `gait_planner.ocp`: constraints,
their Jacobian, the mass matrix, gravity, the discrete Euler-Lagrange equations and the
mirror map are written again from docs/design.md sections 1-3 and 5-7, so an error in the
transcription cannot hide itself. `verify_result(result)` records a `PlanResult` with the
real writer into a temporary file and verifies that file (tests always go through the
recording). ``python -m gait_planner.verify RUN.mcap`` prints the report (exit status 0 if
every check passed, 1 if one failed, 2 if the file cannot be read).

Conventions (docs/design.md section 7, the planner's documented conventions):
nodes 0..N, interval n from t_n to t_{n+1}, h_n = t_{n+1} - t_n. ``active_contacts[n]``
(n < N) are the points held on interval n: they do not move from q_n to q_{n+1}, sit on
the ground, and their published forces (ground on foot, N, world) act in the equation of
node n. Nodes N-1, N are the mirror images of nodes 0, 1 about y = 0 shifted by
``step_length`` s in x and by the ground's rise s tan(slope) + step_height in z; duration and
cost span t_0 .. t_{N-1}.

The ground is the one the metadata names (`gait_planner.verify.ground`, written again here
from docs/design.md section 13; absent entries: level): a ramp (``slope`` deg, the plane
z = x tan(slope), normal n = (-sin, 0, cos)) or stairs (``step_height``, ``stair_riser``,
``stair_tread``; n = e_z); gravity is vertical on every ground. "On the ground" is
n . p = 0 on a ramp and z = the height of the tread under the point on stairs; "normal
force" is n . F, "tangential" F - (n . F) n; the report names the ground.

Checks and method (limits in `LIMITS`):

* Holonomic constraints at every node: internal (6 per body: 1/2(d_i.d_i - 1), d_i.d_j),
  joints (spherical: 3 gap rows; revolute: gap + 2 alignment rows n_p.(D_c a),
  n_p.(D_c b) with a, b completing the axis n to an orthonormal basis), planar root
  (phi_y = y0 of the scene's initial pose, d2.e_x = d2.e_z = 0).
* Contacts: over every held interval a held point does not move and sits on the ground; a
  body in full contact (both its points held) does not move at all and, in 3D, lies flat
  on it (n . d2 = 0); the published contact points equal phi + X_i d_i; no contact point of the
  scene is below the ground at any node (not a failure for scenes whose gait options set
  ``ground_clearance: false``, e.g. the rigid-legged compass, which must scuff: reported).
* Discrete Euler-Lagrange equations at nodes n = 1..N-1, in full (k rows), with the
  recorded q, times, generalized_force and contact forces:
      b = D2 L_d(q_{n-1}, q_n, h_{n-1}) + D1 L_d(q_n, q_{n+1}, h_n) + gen_n
          + w_n sum_points C_p^T F_p,   w_n = (h_{n-1} + h_n)/2,
  where a ground force F on body point X adds F to the body's phi rows and X_i F to its
  d_i rows. Unknown: the internal/joint/planar multipliers, and for every 3D full contact
  the moment about the heel-toe line, which two point forces cannot carry and which is not
  published; the planner applies it as a generalised force along the foot's roll row
  n . d2 (w_n E M_roll, E = n in the foot's d2 entries: its z-component on level ground).
  These unknowns are fitted by linear least squares,
  b + w_n E M_roll = G^T(q_n) y, and the residual is judged relative to
  max(|D2 L_d|, |D1 L_d|, |gen_n|, |contact term|) (2-norms). M_roll is reported, with the
  lateral centre-of-pressure offset |M_roll| / n . F it implies.
* Actuation is internal and made of joint couples: generalized_force is zero on phi and of
  the pure-couple form f_{d_i} = 1/2 m_b x d_i with m_b = sum_i d_i x f_{d_i} (the body's
  couple); the body couples sum to zero (no net moment). Joint couples are recovered
  exactly from the body couples on the tree, leaves first: m_j = m_child(j) +
  sum of the couples of the joints below child(j) (a joint acts +m_j on its child and -m_j
  on its parent). A revolute joint's couple must be parallel to its axis D_p n. The
  recorded efforts must produce these couples. JointTrajectory effort[n] is the node
  torque tau_n conjugate to the joint angles at node n (gait_planner.io.messages):
  revolute, about the axis; spherical, the couple's
  projections on the parent's d2 (pitch), the roll axis (d2_p x d3_c normalised) and the
  child's d3 (yaw), so the world couple follows from a 3x3 solve at q_n. Torques are
  node values (linear between nodes, trapezoidal virtual work), and the check is
  m_j(n) = w_n D_p(q_n) tau_n, w_n = (h_{n-1} + h_n)/2 (node 0 and N: one half interval).
* Contact forces push (n . F of every point >= 0) and lie in the Coulomb cone about n,
  |F - (n . F) n| <= mu n . F, of the body's net force (full contact: heel + forefoot),
  mu = metadata ``friction_coefficient``.
* Periodicity: q_{N-1}, q_N equal the mirror images of q_0, q_1 shifted by the step
  length and the rise (phi' = S phi, d1' = S d1, d2' = -S d2, d3' = S d3 in the partner body,
  S = diag(1, -1, 1)); the contact forces of nodes 0, N are the mirror images (S F) of
  those of nodes N-1, 1; the joint couples of nodes N-1, N are the mirror images of those
  of nodes 0, 1 (a couple m mirrors to -S m, or to +S m when the mirror swaps the joint's
  parent and child). On stairs the tread depth is the step length (each half cycle lands
  a tread further).
* Physical plausibility (`gait_planner.verify.physical`): per-point friction cones, no
  swing point at ground height, on stairs no swing segment through the stairs, strike
  speed along the ground, joint speeds, no torque zigzag away from contact switches.
* Continuous dynamics (`gait_planner.verify.continuous`): Pinocchio's inverse dynamics of
  the continuous model at every inner node from the recorded motion and foot wrenches,
  against the published efforts (torque error within 0.2 % of the peak away from contact
  switches, 2 % at them) and a free floating base (residual force and moment).
* Legs apart (`gait_planner.verify.legs`; scenes whose lower legs carry collision spheres):
  the smallest distance between the collision geometry of the two legs at every node,
  by coal on the URDF's own geometry for a drafted scene, between the spheres otherwise;
  the legs touching (distance <= 0) fails, closer than the plan's leg_clearance is noted.
* Time and cost: times strictly increasing, interval lengths = base_time_step * sigma of
  their phase (when the metadata states base_time_step), sigma within the scaling
  bounds, duration = t_{N-1} - t_0, cost recomputed from q, times and efforts
  (kinetic_energy = sum_{n<N-1} h_n 1/2 v_n^T M v_n, torque_squared =
  sum_{n<N-1} h_n (|tau_n|^2 + |tau_{n+1}|^2)/2 with the planner's node torques tau_n
  recovered from the efforts),
  potential energy = sum m g phi_z. sigma may exceed its bounds by LIMITS["scaling"]
  (IPOPT relaxes bounds by up to its bound_relax_factor).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path
from typing import Sequence

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.verify.checks import verify_plan
from gait_planner.verify.continuous import ContinuousCertificate
from gait_planner.verify.recorded import certificate_of_recording
from gait_planner.verify.physical import PhysicalReport, check_physical
from gait_planner.verify.mechanics import Mechanics, SceneData, parse_scene
from gait_planner.verify.limits import LIMITS
from gait_planner.verify.report import VerificationReport

__all__ = ["LIMITS", "SceneData", "Mechanics", "VerificationReport", "parse_scene",
           "ContinuousCertificate", "certificate_of_recording", "PhysicalReport", "check_physical",
           "verify_plan", "verify_recording", "verify_result", "main"]


def verify_recording(path: str | Path) -> VerificationReport:
    """Read the MCAP recording at `path` and check it (module docstring)."""
    return verify_plan(read_plan_mcap(path))


def verify_result(result) -> VerificationReport:
    """Record `result` (a `PlanResult`) with the real MCAP writer into a temporary file
    and verify that file. Raises ValueError for results the writer refuses (no nodes,
    NaN ...)."""
    from gait_planner.io.mcap_writer import write_plan_mcap  # the writer, only here

    with tempfile.TemporaryDirectory(prefix="gait_verify_") as folder:
        path = Path(folder) / f"{result.scene.name}.mcap"
        write_plan_mcap(result, path)
        return verify_recording(path)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m gait_planner.verify",
        description="Independently check the MCAP recording(s) of planned gaits.")
    parser.add_argument("recordings", nargs="+", help="MCAP files written by the planner")
    args = parser.parse_args(argv)
    status = 0
    for path in args.recordings:
        try:
            report = verify_recording(path)
        except (OSError, ValueError, KeyError, TypeError) as error:
            print(f"{path}: cannot be checked: {error}", file=sys.stderr)
            status = max(status, 2)
            continue
        print(report.summary())
        if not report.ok:
            status = max(status, 1)
    return status


