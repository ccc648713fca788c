"""A walk in words: the summary `gait-planner walk`, `plan --walk` and the node print or log,
and the progress note of a half cycle's end (`walk_plan.walk`'s `progress`).
"""

from __future__ import annotations

from typing import Any

from gait_planner.walk.touches import described

__all__ = ["format_summary", "half_cycles_done", "slid"]


def half_cycles_done(walked: int, steps: int) -> str:
    """"k of K half cycles done": the note of `walk`'s progress(walked, steps), which the
    command line prints as "-- walking (...)" and the node sends as the action phase."""
    return f"{walked} of {steps} half cycles done"


def format_summary(r: dict[str, Any]) -> str:
    """The summary `r` of `walk_plan.walk` (with the command's "out", "rrd" and "self_test"
    when present) as lines: angles in deg, torques in N m, distances in m."""
    lines = [f"{r['scene']} ({r['recording']}): walked {r['half_cycles_walked']} of "
             f"{r['steps']} half cycles in {r['time_walked_s']:.3f} s: {r['stopped']}",
             f"  joint error vs plan   RMS {r['joint_rms_deg']:.2f} deg, max "
             f"{r['joint_max_deg']:.2f} deg",
             f"  feedback share        {100 * r['feedback_share']:.0f} % (RMS feedback "
             f"{r['feedback_rms_nm']:.1f} N m / RMS plan torque {r['plan_rms_nm']:.1f} N m)",
             "  joint RMS per half cycle (deg): "
             + " ".join(f"{v:.2f}" for v in r["joint_rms_per_half_cycle_deg"]),
             "  torso drift per half cycle (m, x y z): "
             + "; ".join(" ".join(f"{v:+.3f}" for v in d) for d in r["torso_drift_m"]),
             "  foot placement error per half cycle (m): "
             + " ".join(f"{v:.3f}" for v in r["foot_placement_error_m"]),
             f"  unplanned touches     {described(r['unplanned_touches'])}",
             f"  largest foot slide    {slid(r['foot_slide'])}"]
    if "out" in r:
        lines.append(f"  recorded in {r['out']}")
    if "rrd" in r:
        lines.append(f"  rerun view in {r['rrd']} (open it with `rerun {r['rrd']}`)")
    for row in r.get("self_test", []):
        lines.append(f"  self-test, plan torques x{row['torque_scale']:g}: "
                     f"{row['half_cycles_walked']} half cycles, feedback share "
                     f"{100 * row['feedback_share']:.0f} %: "
                     f"{'worse (the check can fail)' if row['worse'] else 'NOT worse'}")
    return "\n".join(lines)


def slid(slide: dict[str, Any] | None) -> str:
    """The walk's largest foot slide (`walk.slides.Slides.summary`) in words."""
    if slide is None:
        return "none (no point stood)"
    return (f"{slide['slide_mm']:.1f} mm ({slide['point']} standing {slide['start_s']:.3f}-"
            f"{slide['end_s']:.3f} s, tangential / normal force {slide['friction_used']:.2f})")
