"""The report of the independent verifier (its limits: `gait_planner.verify.limits`)."""

from __future__ import annotations

from dataclasses import dataclass

from gait_planner.verify.continuous import ContinuousCertificate
from gait_planner.verify.legs import LegClearance
from gait_planner.verify.physical import PhysicalReport
from gait_planner.verify.report_text import report_lines


# ----------------------------------------------------------------------------- the report


@dataclass(frozen=True)
class VerificationReport:
    """Every measured number of one recording's checks; `failures` holds one sentence per
    failed check (empty: `ok`), `notes` what was measured but not judged.

    Units: m for positions, N for forces, N s for generalised forces (impulses), N m for
    moments, J s for the kinetic-energy cost; "relative" numbers are dimensionless."""

    path: str
    scene: str
    ground: str  # the ground checked against (`RecordedGround.describe`: "ramp 10 deg up")
    cost_name: str
    n_nodes: int
    planner_success: bool
    max_internal_violation: float
    max_joint_violation: float
    max_planar_violation: float
    max_contact_drift: float  # held point (and full-contact body) motion over an interval
    max_contact_height: float  # held points' distance from the ground (RecordedGround.above)
    max_full_contact_roll: float  # |n . d2| of bodies in 3D full contact (n: ground normal)
    max_contact_point_error: float  # published points vs phi + X_i d_i
    min_contact_point_height: float  # lowest contact point above the ground, any node
    max_dynamics_residual: float  # relative
    worst_dynamics_node: int
    max_dynamics_residual_absolute: float  # N s
    max_roll_moment: float  # N m
    max_roll_offset: float  # m, |M_roll| / F_z of full contacts
    max_actuation_phi: float  # relative
    max_couple_form_error: float  # relative
    max_net_moment: float  # relative
    max_revolute_off_axis: float  # relative
    max_effort_mismatch: float  # relative
    min_normal_force: float  # N, smallest n . F of an active point
    max_friction_ratio: float  # max |F - (n . F) n| / (mu n . F) of each foot's net force
    max_friction_excess: float  # N, max |F - (n . F) n| - mu n . F
    friction_coefficient: float
    max_periodicity_error: float  # m
    max_periodic_force_error: float  # relative
    max_periodic_torque_error: float  # relative
    cost_recorded: float
    cost_recomputed: float
    cost_relative_error: float
    duration_recorded: float
    duration_recomputed: float
    max_interval_error: float  # relative, h_n vs base_time_step * sigma
    max_scaling_bound_excess: float  # relative; <= 0: sigma within its bounds
    max_potential_energy_error: float  # relative
    failures: tuple[str, ...]
    notes: tuple[str, ...] = ()
    physical: PhysicalReport | None = None  # per-point cones, swing clearance, speeds, torques
    continuous: ContinuousCertificate | None = None  # inverse dynamics of the continuous model
    # a robot drafted from its URDF: joint -> (largest |effort| / URDF limit, node, limit N m)
    effort_shares: dict[str, tuple[float, int, float]] | None = None
    legs: LegClearance | None = None  # the legs' smallest distance (scenes with leg spheres)

    @property
    def ok(self) -> bool:
        return not self.failures

    def summary(self) -> str:
        """The report a person reads: the checks grouped by what they test, one line each
        with its value, unit, limit and mark (ok / FAILED / noted / blank: measured, not
        judged), then notes, the failures' sentences and a last verdict line (the
        verifier's: `failures`)."""
        return "\n".join(report_lines(self))

    __str__ = summary
