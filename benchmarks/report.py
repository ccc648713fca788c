"""Write benchmarks/REPORT.md from benchmarks/results/*.json (`bench.py` runs the scripts
that write them, then this). Every number in the report comes from those files; a section
whose file is missing says so. Conclusions are computed from the rows, not typed in.

    .venv/bin/python benchmarks/report.py
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from results_io import HERE, OTHER, RESULTS, load_results


def fmt(v, spec: str = ".3g") -> str:
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    return format(v, spec) if isinstance(v, (int, float)) else str(v)


def table(rows: list[dict], columns: list[tuple[str, str, str]]) -> list[str]:
    """Markdown table: columns (title, key, format spec)."""
    out = ["| " + " | ".join(t for t, _, _ in columns) + " |",
           "|" + "---|" * len(columns)]
    for r in rows:
        out.append("| " + " | ".join(fmt(r.get(k), f) for _, k, f in columns) + " |")
    return out


def _limits(value) -> str:
    """A time limit (s) or one per scene, in words."""
    if isinstance(value, dict):
        return ", ".join(f"{v:g} s ({k})" for k, v in value.items())
    return f"{value} s"


def provenance(doc: dict) -> str:
    h = doc["header"]
    return (f"*Measured {h['date_utc']} on {h['cpu']} ({h['cores']} cores, load "
            f"{h['load_average_1min']:.1f} at the start), commit {h['commit'][:12]}, "
            f"CasADi {h['casadi']}{', quick run' if h.get('quick') else ''}.*")


def time_to_reach(rows, level, key, time_key="solve_time_s"):
    """Solve time (`time_key`) at which the error `key` first drops to `level` (log-log
    interpolation between the grids that bracket it); None if never."""
    pts = sorted((r[time_key], r[key]) for r in rows
                 if r.get(key) is not None and r["converged"])
    best = np.inf
    for i, (t, e) in enumerate(pts):
        if e <= level:
            if i == 0 or best == np.inf:
                return t
            t0 = pts[i - 1][0]
            w = np.log(level / best) / np.log(e / best) if e < best else 1.0
            return float(np.exp(np.log(t0) + w * np.log(t / t0)))
        best = min(best, e)
    return None


def work_precision(doc) -> list[str]:
    out = ["## 1. Speed against error: DMOCC and direct collocation", ""]
    if doc is None:
        return out + ["Not measured (run `make bench`).", ""]
    rows = doc["rows"]
    out += [provenance(doc), "",
            "Both methods solve the same problem (scene, contact phases, free phase durations, "
            "friction cones, mirror periodicity, posture limits, cost) cold from the same "
            "kinematic guess with the same IPOPT options; n intervals per phase with the base "
            "time step scaled by 8/n. *Physics*: the plan's torques and contact schedule "
            "through Pinocchio's continuous dynamics (DOP853, rtol 1e-10) over one interval "
            "from every node (RMS and max joint-angle drift) and over each phase; "
            "*reference*: DMOCC at "
            f"{doc['header'].get('reference', '?')} intervals per phase, joint angles at equal "
            "phase-relative times; *certificate*: inverse dynamics, largest torque error in % "
            "of the peak torque away from contact switches. The collocation (recursive "
            "Newton–Euler dynamics) runs as DMOCC does: its rows as per-point, per-knot and "
            "per-interval elements whose derivatives are compiled to C (`collocation`, the "
            "baseline), and for comparison with CasADi's derivatives of the one expanded SX "
            "graph (`collocation_interpreted`); every IPOPT instance is built before the clock "
            "starts. Time limit per collocation solve: "
            f"{_limits(doc['header'].get('collocation_time_limit_s', '?'))}. Per iteration: "
            "*eval* is IPOPT's time in f, g and their derivatives, *KKT* its wall time less "
            "that and the progress callback (mostly MUMPS), in ms.", "",
            "![work-precision](work_precision.png)", ""]
    for r in rows:
        its = max(r.get("iterations") or 0, 1)
        r["eval_ms"] = 1e3 * r["evaluation_s"] / its if r.get("evaluation_s") is not None else None
        r["kkt_ms"] = 1e3 * r["kkt_s"] / its if r.get("kkt_s") is not None else None
    out += table(rows, [
        ("scene", "scene", ""), ("method", "method", ""), ("n", "intervals_per_phase", "d"),
        ("variables", "variables", "d"), ("iterations", "iterations", "d"),
        ("build s", "build_time_s", ".1f"), ("solve s", "solve_time_s", ".2f"),
        ("eval ms/it", "eval_ms", ".3g"), ("KKT ms/it", "kkt_ms", ".3g"),
        ("converged", "converged", ""),
        ("J", "cost", ".5f"), ("physics RMS deg", "error_physics_rms_deg", ".3g"),
        ("physics max deg", "error_physics_max_deg", ".3g"),
        ("phase max deg", "error_physics_phase_max_deg", ".3g"),
        ("certificate %", "certificate_torque_calm_pct", ".3g"),
        ("reference RMS deg", "error_reference_rms_deg", ".3g"),
        ("J vs reference", "cost_reference_relative", "+.2%")])
    out.append("")
    lines = []
    for scene in dict.fromkeys(r["scene"] for r in rows):
        for key, what in (("error_physics_rms_deg", "physics RMS"),
                          ("error_reference_rms_deg", "reference RMS")):
            mine = {m: [r for r in rows if r["scene"] == scene and r["method"] == m]
                    for m in ("dmocc", "collocation")}
            errors = sorted(r[key] for rs in mine.values() for r in rs
                            if r.get(key) is not None and r["converged"])
            if not errors:
                continue
            for level in sorted({errors[len(errors) // 2], errors[-1]}):
                t = {m: time_to_reach(rs, level, key) for m, rs in mine.items()}
                ratio = (f"collocation/DMOCC = {t['collocation'] / t['dmocc']:.2g}"
                         if t["dmocc"] and t["collocation"] else "one method never reaches it")
                lines.append(f"| {scene} | {what} ≤ {level:.3g} deg | {fmt(t['dmocc'], '.2f')} "
                             f"| {fmt(t['collocation'], '.2f')} | {ratio} |")
    if lines:
        out += ["Time to reach a given error (solve time, s; interpolated between grids):", "",
                "| scene | error | DMOCC s | collocation s | ratio |", "|---|---|---|---|---|",
                *lines, ""]
    out += conclusions(rows)
    return out


def conclusions(rows) -> list[str]:
    out = ["**Conclusion (computed from the rows above).**"]
    for scene in dict.fromkeys(r["scene"] for r in rows):
        ok = {m: [r for r in rows if r["scene"] == scene and r["method"] == m and r["converged"]]
              for m in ("dmocc", "collocation")}
        fails = {m: sum(1 for r in rows if r["scene"] == scene and r["method"] == m
                        and not r["converged"]) for m in ok}
        if not ok["dmocc"] or not ok["collocation"]:
            out.append(f"- {scene}: DMOCC converged on {len(ok['dmocc'])} grids, collocation on "
                       f"{len(ok['collocation'])} (failures: DMOCC {fails['dmocc']}, "
                       f"collocation {fails['collocation']}); no side-by-side comparison.")
            continue
        t = {m: np.median([r["solve_time_s"] for r in rs]) for m, rs in ok.items()}
        e = {m: np.median([r["error_physics_rms_deg"] for r in rs]) for m, rs in ok.items()}
        faster = "DMOCC" if t["dmocc"] < t["collocation"] else "collocation"
        closer = "DMOCC" if e["dmocc"] < e["collocation"] else "collocation"
        out.append(f"- {scene}: median solve time DMOCC {t['dmocc']:.2f} s against collocation "
                   f"{t['collocation']:.2f} s ({faster} faster); median one-interval physics "
                   f"error {e['dmocc']:.3g} against {e['collocation']:.3g} deg ({closer} closer "
                   f"to the continuous dynamics); failures to converge: DMOCC {fails['dmocc']}, "
                   f"collocation {fails['collocation']}.")
    return out + [""]


def integrators(doc) -> list[str]:
    out = ["## 2. Forward integration: the variational integrator against RK45 and DOP853", ""]
    if doc is None:
        return out + ["Not measured.", ""]
    rows = doc["rows"]
    out += [provenance(doc), "",
            "walker3d hanging from its pinned right heel, gravity, seeded random rates "
            "(passive) and random joint torques (actuated); the RK methods integrate a "
            "Pinocchio model re-rooted at the heel from the same state. Energy error "
            "|E - W - E(0)| / max T (W: work of the torques); trajectory error: RMS distance "
            "of the bodies' centres of mass from DOP853 at rtol 1e-13 (short horizon only: "
            "the motion is chaotic).", "", "![integrators](integrators.png)", ""]
    out += table(rows, [
        ("horizon", "horizon", ""), ("motion", "motion", ""), ("method", "method", ""),
        ("dt / rtol", "dt_or_rtol", ".0e"), ("wall s", "wall_s", ".2f"),
        ("evaluations", "evaluations", "d"), ("energy error max", "energy_error_max", ".2e"),
        ("median, first tenth", "energy_error_median_first_tenth", ".2e"),
        ("median, last tenth", "energy_error_median_last_tenth", ".2e"),
        ("trajectory RMS m", "trajectory_error_rms", ".2e")])
    drift = []
    for r in rows:
        a, b = r.get("energy_error_median_first_tenth"), r.get("energy_error_median_last_tenth")
        if r.get("horizon") == "long" and a and b:
            drift.append((r["method"], r["motion"], r["dt_or_rtol"], b / a))
    if drift:
        vi = [d for d in drift if d[0] == "VI"]
        rk = [d for d in drift if d[0] != "VI"]
        out += ["", "**Conclusion (computed).** Over the long horizon the energy error's median "
                "grows from the first to the last tenth by a factor of "
                f"{fmt(min(d[3] for d in vi), '.2g')}–{fmt(max(d[3] for d in vi), '.2g')} for the "
                f"variational integrator and {fmt(min(d[3] for d in rk), '.2g')}–"
                f"{fmt(max(d[3] for d in rk), '.2g')} for the RK methods: the VI's error is "
                "bounded, the RK methods drift; at equal wall time the tight-tolerance RK "
                "methods are nonetheless far more accurate on these horizons (table)."]
    return out + [""]


def model_size(doc) -> list[str]:
    out = ["## 3. What a smaller model buys", ""]
    if doc is None:
        return out + ["Not measured.", ""]
    rows = doc["rows"]
    out += [provenance(doc), "", "Each scene's default request, derivatives "
            f"{rows[0]['derivatives']}; the solve includes the kinematic guess.", ""]
    out += table(rows, [
        ("scene", "scene", ""), ("dof", "dof", "d"), ("N", "intervals", "d"),
        ("variables", "variables", "d"), ("constraints", "constraints", "d"),
        ("Jacobian nnz", "jacobian_nonzeros", "d"), ("Hessian nnz (upper)", "hessian_nonzeros", "d"),
        ("build s", "build_s", ".2f"), ("solve s", "solve_s", ".2f"),
        ("iterations", "iterations", "d"), ("ms/iteration", "per_iteration_ms", ".1f"),
        ("J", "cost", ".4f")])
    return out + [""]


def hard_cases(doc) -> list[str]:
    out = ["## 4. Hard requests", ""]
    if doc is None:
        return out + ["Not measured.", ""]
    rows = doc["rows"]
    out += [provenance(doc), "",
            f"The scene's default request changed in one way, cold, time limit "
            f"{doc['header'].get('time_limit_s', '?')} s per plan. A converged plan is checked "
            "by `gait_planner.verify` (DMOCC: every check; collocation: the physical checks "
            "and the continuous-dynamics certificate, as the discrete checks are DMOCC's own "
            "equations).", ""]
    out += table(rows, [
        ("case", "case", ""), ("scene", "scene", ""), ("method", "method", ""),
        ("outcome", "outcome", ""), ("intervals", "intervals", ""),
        ("iterations", "iterations", "d"), ("wall s", "wall_s", ".1f"), ("J", "cost", ".4f"),
        ("constraint violation", "max_constraint_violation", ".1e"),
        ("reason", "reason", "")])
    return out + [""]


def request_sweep(doc) -> list[str]:
    out = ["## 6. Cold plans over a spread of requests", ""]
    if doc is None:
        return out + ["Not measured.", ""]
    out += [provenance(doc), "",
            "`request_sweep.py`: one process per scene plans cold from the kinematic guess at "
            "five step lengths and two friction coefficients (compiled derivatives, "
            f"{doc['header'].get('time_limit_s', '?')} s per plan). Iteration counts change with "
            "round-off request by request; the totals are what a change of formulation is "
            "judged by.", ""]
    out += table(doc["rows"], [
        ("scene", "scene", ""), ("step m", "step_length", ".2f"),
        ("mu", "friction_coefficient", ".1f"),
        ("converged", "success", ""), ("iterations", "iterations", "d"),
        ("solve s", "solve_s", ".2f"), ("J", "cost", ".4f")])
    totals = [{"scene": scene, **t} for scene, t in doc["header"]["totals"].items()]
    return out + [""] + table(totals, [
        ("scene", "scene", ""), ("converged", "converged", "d"), ("requests", "requests", "d"),
        ("iterations in all", "iterations", "d"), ("solve s in all", "solve_s", ".1f")]) + [""]


def speed(cold, node) -> list[str]:
    out = ["## 5. Speed as a user meets it (fresh processes)", ""]
    if cold is not None:
        out += [provenance(cold), "", "`cold_solve.py`: each run a new process (imports, build "
                "from the compiled cache, cold plan, warm re-plan at step length +2 %); the cold plan's "
                "time per iteration split by IPOPT's timers (evaluation, the primal-dual system "
                "MUMPS factorises and solves, the rest of IPOPT) and the time outside IPOPT "
                "(guess, result), from one more process per scene with the timers on; "
                "medians:",
                ""]
        rows = [{"scene": s, **m} for s, m in cold["header"]["medians"].items()]
        out += table(rows, [
            ("scene", "scene", ""), ("ready s", "ready_s", ".2f"), ("cold s", "cold_s", ".2f"),
            ("iterations", "cold_iterations", ".0f"), ("ms/iteration", "cold_per_iteration_ms", ".1f"),
            ("evaluation share", "cold_evaluation_share", ".0%"),
            ("evaluation ms/it.", "cold_evaluation_ms", ".1f"),
            ("KKT (MUMPS) ms/it.", "cold_kkt_ms", ".1f"),
            ("rest of IPOPT ms/it.", "cold_other_ipopt_ms", ".1f"),
            ("outside IPOPT s", "cold_outside_ipopt_s", ".3f"), ("warm s", "warm_s", ".3f"),
            ("warm iterations", "warm_iterations", ".0f")]) + [""]
    if node is not None:
        rows = node["rows"]
        med = {(library, k): float(np.median([r[k] for r in rows
                                               if r.get("library", False) == library]))
               for library in (False, True) if any(r.get("library", False) == library for r in rows)
               for k in ("service_ready_s", "first_answer_s", "first_answer_from_start_s",
                         "warm_answer_s", "first_iterations", "warm_iterations")
               if all(k in r for r in rows)}
        out += [provenance(node), "", f"`node_latency.py`: {len(rows)} fresh `gait-planner node` "
                f"processes (walker3d, the default request), without and with the warm-start store "
                f"as `make setup` leaves it (the default plan only). Medians:", ""]
        out += table([{"kind": "with the warm-start store" if library else "without (cold)",
                       **{k: v for (lib, k), v in med.items() if lib == library}}
                      for library in (False, True) if (library, "first_answer_s") in med], [
            ("node", "kind", ""), ("service offered s", "service_ready_s", ".2f"),
            ("first answer s", "first_answer_s", ".2f"),
            ("first answer from the process start s", "first_answer_from_start_s", ".2f"),
            ("first iterations", "first_iterations", ".0f"),
            ("warm answer (+2 %) s", "warm_answer_s", ".2f"),
            ("warm iterations", "warm_iterations", ".0f")]) + [""]
    return out


def walk(doc) -> list[str]:
    out = ["## 7. Plans walked in MuJoCo", ""]
    if doc is None:
        return out + ["Not measured.", ""]
    steps = doc["header"].get("steps", "?")
    out += [provenance(doc), "",
            f"`walk.py`: each plan made by `gait-planner plan --cold-start` (time limit "
            f"{doc['header'].get('time_limit_s', '?')} s), then walked {steps} half cycles by "
            "`gait-planner walk` (config/walk.yaml) and again with the plan's torques scaled "
            "down (the self-test: the feedback must not do the plan's work). Feedback share: "
            "RMS feedback / RMS plan torque; drift: the torso's distance from the plan (x y z) "
            "after the last half cycle walked; placement: the worst distance of a held contact "
            "point from the plan's at a half cycle's end; unplanned touches: a contact point "
            "carrying over a tenth of the weight where the plan holds it at neither "
            "neighbouring node (`gait_planner.walk.touches`: an early strike if the plan "
            "strikes it within 0.1 s, else a scuff), how many and the first; largest foot "
            "slide: how far a contact point moved along the ground while it carried over a "
            "tenth of the weight (`gait_planner.walk.slides`), the point and its mean "
            "tangential / normal force. The hard "
            "requests are `hard_cases.py`'s a user can ask for (plan options or a changed "
            "scene file).", ""]
    rows = [dict(r, planned=(f"{r['plan'].get('nodes')} nodes, {r['plan']['wall_s']:.0f} s"
                             + ("" if r["plan"].get("certified") else ", certificate fails")
                             if r["plan"]["success"] else "failed"),
                 walked=("–" if r["half_cycles_walked"] is None
                            else f"{r['half_cycles_walked']} of {r['steps']}"),
                 drift=" ".join(f"{x:+.3f}" for x in r.get("torso_drift_last_m") or []),
                 selftest=_self_test(r["self_test"]),
                 touches=_touches(r.get("unplanned_touches"), r.get("unplanned_touch_count")),
                 slide=_slide(r.get("foot_slide")))
            for r in doc["rows"]]
    return out + table(rows, [
        ("scene", "scene", ""), ("case", "case", ""), ("plan", "planned", ""),
        ("half cycles walked", "walked", ""),
        ("feedback share", "feedback_share", ".0%"), ("joint RMS deg", "joint_rms_deg", ".2f"),
        ("joint max deg", "joint_max_deg", ".1f"), ("drift m", "drift", ""),
        ("placement m", "foot_placement_error_max_m", ".3f"),
        ("unplanned touches (first)", "touches", ""),
        ("largest foot slide", "slide", ""),
        ("self-test: walked (feedback)", "selftest", ""), ("why it stopped", "stopped", "")]) + [""]


def _self_test(tests: list[dict]) -> str:
    """A walk's self-test in words: each torque scale's half cycles walked (feedback)."""
    return ", ".join(f"×{t['torque_scale']:g}: {t['half_cycles_walked']} "
                     f"({t['feedback_share']:.0%})" for t in tests)


def _touches(touches: list[dict] | None, count: int | None) -> str:
    """A walk's unplanned touches in words (`gait_planner.walk.touches.described`); – if
    the run did not record them."""
    from gait_planner.walk.touches import described

    return "–" if touches is None else described(touches, count)


def _slide(slide: dict | None) -> str:
    """A walk's largest foot slide: mm (point, tangential / normal force); – if the run
    did not record it or no point stood."""
    if not slide:
        return "–"
    return f"{slide['slide_mm']:.0f} mm ({slide['point']}, {slide['friction_used']:.2f})"


def model_error(doc) -> list[str]:
    """Section 7's table of plans walked on a walker that is not the plan's model."""
    out = ["### A walker that is not the plan's model", ""]
    if doc is None:
        return out + ["Not measured (`model_error.py`).", ""]
    h = doc["header"]
    out += [provenance(doc), "",
            f"`model_error.py`: the default plans walked {h.get('steps', '?')} half cycles "
            "by the same controller on a MuJoCo walker changed as a robot differs from its "
            "URDF (`gait_planner.walk.model_error`; the command delay delays the feed-forward, "
            "the torso feedback and the joint targets, each joint's own PD acting on its "
            "present state; "
            + ("the controller computes each command for the state it will meet, predicted on "
               "the nominal walker through the delay: `delay.predict`, `gait_planner.walk."
               "predictor`" if h.get("delay_predict") else "the controller acts on the present "
               "state") + "). Perturbed walks that completed every half cycle: "
            f"**{h.get('completed_share', float('nan')):.0%}** (target 90 %).", ""]
    rows = [dict(r, done=f"{r['completed']} of {r['walks']}",
                 cycles=f"{r['half_cycles_min']} / {r['half_cycles_median']:g}",
                 why="; ".join(r["stopped"]) or "–") for r in doc["rows"]]
    return out + table(rows, [
        ("scene", "scene", ""), ("perturbation", "perturbation", ""),
        ("walks completed", "done", ""), ("half cycles min / median", "cycles", ""),
        ("feedback share median", "feedback_share_median", ".0%"),
        ("feedback share max", "feedback_share_max", ".0%"),
        ("what stopped the others", "why", "")]) + [""]


def _monotone(values: list[float]) -> str:
    """"rises", "falls" or "not monotone" for a series in order."""
    d = np.diff(values)
    return "rises" if np.all(d > 0) else "falls" if np.all(d < 0) else "not monotone"


def smoothness(doc) -> list[str]:
    """Section 7's table of the terminal swing's torques (`smoothness.py`)."""
    out = ["### A terminal swing without a burst", ""]
    if doc is None:
        return out + ["Not measured (`smoothness.py`).", ""]
    h = doc["header"]
    out += [provenance(doc), "",
            "`smoothness.py`: the default plans as shipped, with the swing braked over its "
            "swing (`strike_deceleration_max`, m/s²) and with the torques' second differences "
            "in the cost (`torque_smoothness`, per (N m)², the J reported without it), each a "
            "gait option in a copy of the scene file, each plan made by `gait-planner plan "
            "--cold-start` (time limit "
            f"{h.get('time_limit_s', 300):g} s), checked by the verifier and walked "
            f"{h.get('steps', '?')} half cycles with the self-test. Away from contact "
            "switches, the largest second difference of a joint torque between nodes: over the "
            f"largest joint peak (target ≤ {h.get('target_of_peak', 0.2):.0%}), and over its "
            "own joint's peak for joints above a fifth of the largest "
            f"(target ≤ {h.get('target_of_own_peak', 0.25):.0%}).", ""]
    rows = [dict(r, J=r["plan"].get("cost_value"), it=r["plan"].get("iterations"),
                 nodes=r["plan"].get("nodes"),
                 own=(f"{r['roughest_own_peak']:.1%} ({r['roughest_joint']}, node "
                      f"{r['roughest_node']})" if "roughest_own_peak" in r else "–"),
                 checks="pass" if r.get("checks_pass") else "fail",
                 target="yes" if r.get("meets_target") else "no",
                 walked=("–" if r.get("half_cycles_walked") is None
                         else f"{r['half_cycles_walked']} of {r['steps']}"),
                 selftest=_self_test(r.get("self_test", [])))
            for r in doc["rows"]]
    return out + table(rows, [
        ("scene", "scene", ""), ("plan", "case", ""), ("J", "J", ".4f"),
        ("iterations", "it", ""), ("nodes", "nodes", ""),
        ("second difference / largest peak", "second_difference_of_peak", ".1%"),
        ("/ own peak (joint, node)", "own", ""), ("targets met", "target", ""),
        ("checks", "checks", ""), ("half cycles walked", "walked", ""),
        ("feedback share", "feedback_share", ".0%"),
        ("self-test: walked (feedback)", "selftest", "")]) + [""]


def gait_trends(doc) -> list[str]:
    out = ["## 8. Work, torques and powers over slope and speed, against human trends", ""]
    if doc is None:
        return out + ["Not measured.", ""]
    rows = doc["rows"]
    out += [provenance(doc), "",
            "`gait_trends.py`: one certified cold plan per row (slope at the scene's step and "
            "free durations; speed on level ground at the scene's step; 0.8 m/s at a 0.45 m "
            "step). Work and powers from the published efforts conjugate to the joint angles "
            "over one half cycle; W+/(m g s) the mechanical cost of transport; the stance "
            "knee's peak flexion in single support. Sources of the human trends: the "
            "script's docstring. Figure: [gait_trends.png](gait_trends.png).", ""]
    shown = [dict(r, **({} if not r.get("success") else {
        "torques": " / ".join(f"{r[f'{j}_peak_torque_Nm']:.0f}" for j in ("hip", "knee", "ankle")),
        "powers": " / ".join(f"{r[f'{j}_peak_power_W']:.0f}" for j in ("hip", "knee", "ankle"))}))
        for r in rows]
    out += table(shown, [
        ("scene", "scene", ""), ("series", "series", ""), ("value", "value", "g"),
        ("certified", "certified", ""), ("J", "cost", ".3f"), ("speed m/s", "speed_m_s", ".3f"),
        ("W+ J", "positive_work_J", ".1f"), ("W- J", "negative_work_J", ".1f"),
        ("m g rise J", "rise_work_J", ".1f"), ("W+/(m g s)", "mechanical_cost_of_transport", ".3f"),
        ("hip / knee / ankle peak torque N m", "torques", ""),
        ("hip / knee / ankle peak power W", "powers", ""),
        ("stance knee deg", "stance_knee_flexion_deg", ".1f"), ("wall s", "wall_s", ".0f")])
    out += ["", "Against the human trends (computed from the rows above):", ""]
    for scene in sorted({r["scene"] for r in rows}):
        slope = sorted((r for r in rows if r["scene"] == scene and r["series"] == "slope"
                        and r.get("success")), key=lambda r: r["value"])
        speed = sorted((r for r in rows if r["scene"] == scene and r["series"] == "speed"
                        and r.get("success")), key=lambda r: r["value"])
        if len(slope) > 1:
            out.append(f"* {scene}, slope {slope[0]['value']:g} to {slope[-1]['value']:g} deg: "
                       f"W+ {_monotone([r['positive_work_J'] for r in slope])} (humans: rises), "
                       f"|W-| {_monotone([-r['negative_work_J'] for r in slope])} (humans: "
                       f"falls); hip peak power {_monotone([r['hip_peak_power_W'] for r in slope])}"
                       f" (humans: rises); knee peak torque "
                       f"{_monotone([r['knee_peak_torque_Nm'] for r in slope])}.")
        if len(speed) > 1:
            out.append(f"* {scene}, speed {speed[0]['value']:g} to {speed[-1]['value']:g} m/s: "
                       f"stance knee flexion "
                       f"{_monotone([r['stance_knee_flexion_deg'] for r in speed])} (humans: "
                       f"rises); peak torques hip "
                       f"{_monotone([r['hip_peak_torque_Nm'] for r in speed])}, knee "
                       f"{_monotone([r['knee_peak_torque_Nm'] for r in speed])}, ankle "
                       f"{_monotone([r['ankle_peak_torque_Nm'] for r in speed])} (humans: "
                       f"rise); walks above 2.07 m/s (the human walk-run transition): "
                       f"{sum(r['value'] > 2.07 for r in speed)} planned, no human counterpart.")
    planned = [r for r in rows if r.get("success")]
    if planned:
        knees = [r["stance_knee_flexion_deg"] for r in planned]
        out.append(f"* Stance knee flexion in single support {min(knees):.0f} to {max(knees):.0f} "
                   f"deg in every row, against about 15 to 25 deg in people (Lelas et al. "
                   f"2003): the minimal-kinetic-energy walkers walk crouched; `posture: human` "
                   f"bounds the stance knee to 20 deg (user guide).")
    for scene in sorted({r["scene"] for r in planned}):
        by = {r["value"]: r for r in planned if r["scene"] == scene and r["series"] == "slope"}
        if 0.0 in by and max(by) > 0:
            gains = {j: by[max(by)][f"{j}_peak_power_W"] - by[0.0][f"{j}_peak_power_W"]
                     for j in ("hip", "knee", "ankle")}
            most = max(gains, key=gains.get)
            out.append(f"* {scene}, level to {max(by):g} deg uphill: the {most}'s peak power "
                       f"rises most ({', '.join(f'{j} {g:+.0f} W' for j, g in gains.items())}); "
                       f"in people the hip's does (Lay et al. 2006).")
    failed = [r for r in rows if not r.get("success")]
    if failed:
        out.append("* Not planned: " + "; ".join(
            f"{r['scene']} {r['series']} {r['value']:g}: {r['message']}" for r in failed))
    return out + [""]


def gait_library(doc) -> list[str]:
    out = ["## 9. Gait libraries on Ray", ""]
    if doc is None:
        return out + ["Not measured.", ""]
    rows = doc["rows"]
    builds = [r for r in rows if r["kind"] in ("build", "cluster")]
    serve = [r for r in rows if r["kind"] == "serve"]
    out += [provenance(doc), "",
            "`gait_library.py`: `gait-planner library build` (`gait_planner.gaitlib`) of the "
            f"walker2d grid `{doc['header']['grid']}` into fresh folders: plans per minute of "
            "planning (Ray's start apart), by continuation (a seed per worker cold, every "
            "other point warm from a finished neighbour) or as independent cold plans; the "
            "same on `ray.cluster_utils.Cluster` with 4 one-CPU nodes on this machine (they "
            "share its 2 cores: the build runs unchanged through a cluster address, but no "
            "speed-up can show here). Every recording is checked by the verifier. Figure: "
            "[gait_library.png](gait_library.png).", ""]
    out += table(builds, [
        ("kind", "kind", ""), ("scene", "scene", ""), ("points", "points", "d"),
        ("workers", "workers", ""), ("continuation", "continuation", ""),
        ("Ray start s", "ray_start_s", ".1f"), ("planning s", "planning_s", ".1f"),
        ("plans/min", "plans_per_min", ".1f"), ("IPOPT iterations", "iterations", "d"),
        ("cold points", "cold_points", "d"), ("failed", "failed", "d")])
    bad = [f"{r['scene']} ({r['kind']}, {r['workers']} workers): {', '.join(r['verifier_failures'])}"
           for r in builds if r["verifier_failures"]]
    out += ["", "Recordings failing the verifier: " + ("; ".join(bad) if bad else "none") + "."]
    if serve:
        out += ["", "In-hull answers (walker3d libraries over step length and friction, "
                "requests at the cells' centres, in one process as a node answers them after "
                "its first request: every IPOPT instance built and called once, one plan "
                "stored): from the library's interpolation (IPOPT's barrier fixed at 1e-9), "
                "from the nearest single stored plan (the node without a library), and "
                "cold. Times include reading the library.", ""]
        out += table(serve, [
            ("library grid", "serve_grid", ""),
            ("step m", "step_length", ".4f"), ("mu", "friction_coefficient", ".2f"),
            ("library it", "library_iterations", "d"), ("library s", "library_s", ".3f"),
            ("of which interpolation s", "library_start_s", ".3f"),
            ("nearest it", "nearest_iterations", "d"), ("nearest s", "nearest_s", ".3f"),
            ("cold it", "cold_iterations", "d"), ("cold s", "cold_s", ".2f")])
        out.append("")
        for grid in dict.fromkeys(r["serve_grid"] for r in serve):
            its = [r["library_iterations"] for r in serve if r["serve_grid"] == grid]
            secs = [r["library_s"] for r in serve if r["serve_grid"] == grid]
            out.append(f"From the library `{grid}`: {min(its)} to {max(its)} IPOPT iterations "
                       f"(median {float(np.median(its)):g}), {min(secs):.3f} to "
                       f"{max(secs):.3f} s (median {float(np.median(secs)):.3f} s); target: "
                       "at most 3 iterations and 0.1 s.")
    return out + [""]


PEER_NOTES = {
    "crocoddyl": "Crocoddyl (FDDP, multiple shooting as its biped example writes it: contact "
                 "forward dynamics, 6D sole and 3D point contacts, impulses at touch-down): "
                 "same schedule, placements, durations and mu; it cannot free the start state "
                 "or the durations, makes periodicity a terminal cost and cones, limits and "
                 "the ground barrier costs, and minimises squared torques (+ a small state "
                 "regularisation), not kinetic energy. Its RK4 rows take 4 dynamics "
                 "evaluations per interval; the 'x0 DMOCC' rows start from DMOCC's optimal "
                 "start state (warm), the 'x0 guess' rows from the kinematic guess's.",
    "drake": "Drake (MathematicalProgram, backward Euler or midpoint dynamics from the "
             "plant's mass matrix and bias terms, impulses at touch-down, hard cones: exact in "
             "the plane, an 8-sided pyramid in 3D, hard mirror periodicity and limits, squared "
             "torques, from the kinematic guess): same schedule, placements, durations and "
             "mu; point contacts only (no full-foot roll moment, no foot width), no swing "
             "clearance ramp or strike-speed bound; its IPOPT runs with a limited-memory "
             "Hessian, SNOPT reports function evaluations, not iterations.",
    "opensim": "OpenSim Moco (MocoCasADiSolver: Hermite-Simpson collocation on DMOCC's "
               "nodes, IPOPT with CasADi's finite differences and a limited-memory Hessian, "
               "tolerances 1e-4, as its example2DWalking prediction): the walker as an "
               "OpenSim Model from the URDF (the scene's torso inertia), squared torques, "
               "hard mirror periodicity (controls included), joint ranges, speed limit and "
               "torso lean as bounds, DMOCC's total duration; its contact is Moco's, "
               "compliant (smooth Hunt-Crossley spheres at the contact points against a "
               "half-space, smoothed Coulomb plus viscous friction), so there is no "
               "schedule, no placements, no impacts and no hard cone: the optimiser finds "
               "its own contact sequence and feet may slide or sink a little; the hold and "
               "cone columns measure it against DMOCC's schedule. Moco has no time limit: "
               "a stopped row is its iterate at the limit (Moco's stop file deleted).",
}


PEER_LEVELS = (1.0, 0.5, 0.2)  # one-interval drift RMS, deg: the peers' time-to-reach levels


def peers(docs: dict) -> list[str]:
    out = ["## 10. DMOCC against Crocoddyl, Drake and OpenSim Moco", ""]
    if not docs:
        return out + ["Not measured (`make bench-peers`).", ""]
    every = [r for doc in docs.values() for r in doc["rows"]]
    versions = sorted({f"{r['peer']} {r['version']}" for r in every if r.get("version")})
    out += ["`make bench-peers` (`benchmarks/peers/run.py`, each peer in its own environment "
            "`.venv-peers/<peer>`): the same walker (the project's URDF), DMOCC's contact "
            "schedule, foot placements and phase durations, the same friction coefficient; "
            "every plan measured by the project's instruments: one-interval drift against "
            "the continuous dynamics (Pinocchio, DOP853; RMS and max over the nodes), the "
            "swing foot's drift over a phase, contact points held (mm), cone and joint-limit "
            "violations, the plan's own periodicity gap, and the integral of squared torques "
            "(every method's, whatever it minimised); DMOCC's plan and every converged "
            "peer plan recorded by the product's writer and walked in MuJoCo by the "
            "reference controller (config/walk.yaml), as a user walks a plan: half cycles "
            "walked of 10 and the joints' RMS tracking error. Each scene's table is one run "
            "(its header says so, or says which runs it joins): every row, DMOCC's included, "
            "solved one at a time after the 1-minute load average fell to the threshold, "
            "re-run once when it did not or when the rest of the machine added more than "
            "the threshold during the solve (*load*: before the kept solve; *loaded*: still "
            "so); *thr* the solver's threads. Versions: "
            f"{', '.join(versions) or 'see the requirements files'}. Figure (solve time "
            "against drift, each method's grids joined): [peers.png](peers.png).", ""]
    for scene, doc in docs.items():
        out += peer_table(scene, doc)
    out += ["What is and is not comparable:", "",
            "* DMOCC: frees the start state and the phase durations, imposes periodicity, "
            "cones, limits, swing clearance and strike speed as hard constraints, and minimises "
            "kinetic energy; its row is the plan the product answers with."]
    out += [f"* {text}" for peer, text in PEER_NOTES.items()
            if any(r["peer"] == peer for r in every)]
    return out + [""]


def peer_table(scene: str, doc: dict) -> list[str]:
    """One scene's peer table with its run's provenance, and the time each method takes to
    reach PEER_LEVELS of drift and to a plan that walks 10 half cycles."""
    h, rows = doc["header"], doc["rows"]
    run = ("one run" if h.get("one_run") else
           f"**not one run**: rows of several runs joined (`{h.get('argv', '')}`), each "
           "with its `measured` stamp in the JSON")
    load = (f", load before a solve at most {h['load_before_max']:.2f} (threshold "
            f"{h['load_threshold']}), {h['rows_re_run']} rows re-run, "
            f"{h['rows_under_load']} still under load" if h.get("load_before_max") is not None
            else "")
    out = [f"### {scene}", "", provenance(doc), "",
           f"{run}; threads {h.get('threads', 'not recorded')}{load}; time limit "
           f"{h.get('time_limit_s', 300):g} s per solve (a row saying otherwise had its own).",
           ""]
    out += table(sorted(rows, key=lambda r: (r["grid"], r["method"] != "DMOCC", r["method"])), [
        ("n", "grid", "d"), ("method", "method", ""),
        ("conv", "converged", ""), ("build s", "build_time", ".2g"),
        ("solve s", "solve_time", ".3g"), ("iter", "iterations", ""), ("thr", "threads", ""),
        ("load", "load_before", ".2f"), ("loaded", "under_load", ""),
        ("int tau^2", "squared_torque", ".4g"), ("node RMS deg", "drift_node_rms_deg", ".3g"),
        ("node max deg", "drift_node_max_deg", ".3g"), ("swing mm", "swing_phase_mm", ".3g"),
        ("hold mm", "contact_hold_mm", ".2g"), ("cone N", "cone_violation_n", ".2g"),
        ("limit deg", "joint_limit_deg", ".2g"), ("periodic mm", "plan_periodicity_mm", ".3g"),
        ("walked", "walk_half_cycles", "d"), ("walk RMS deg", "walk_joint_rms_deg", ".3g"),
        ("status", "status", "")])
    methods = {m: [r for r in rows if r["method"] == m and r.get("solve_time") is not None]
               for m in sorted({r["method"] for r in rows}, key=lambda m: (m != "DMOCC", m))}
    dmocc = methods.get("DMOCC", [])
    lines = []
    for method, mine in methods.items():
        cells = []
        for level in PEER_LEVELS:
            t = time_to_reach(mine, level, "drift_node_rms_deg", "solve_time")
            ref = time_to_reach(dmocc, level, "drift_node_rms_deg", "solve_time")
            cells.append("never" if t is None else f"{t:.3g}" + (
                f" ({t / ref:.2g}×)" if ref and method != "DMOCC" else ""))
        walks = [r["solve_time"] for r in mine if r.get("walk_half_cycles") == 10]
        cells.append(f"{min(walks):.3g}" if walks else "none")
        lines.append(f"| {method} | " + " | ".join(cells) + " |")
    levels = " | ".join(f"drift ≤ {v:g} deg" for v in PEER_LEVELS)
    return out + ["", "Time to reach a one-interval drift (RMS over the nodes; solve s, "
                  "converged rows only, interpolated between grids as in section 1; in "
                  "brackets the ratio to DMOCC's time in this run), and the shortest solve "
                  "whose plan walked 10 of 10 half cycles:", "",
                  f"| method | {levels} | walks 10 |",
                  "|---" * (len(PEER_LEVELS) + 2) + "|", *lines, ""]


def _certificate(text: str) -> str:
    """A certificate's sentence in short: OK or fails, with the torque error."""
    if not text:
        return "–"
    match = re.search(r"torque error ([0-9.eE+-]+) %", text)
    return ("OK" if text.endswith(": OK") else "fails") + (f" ({match.group(1)} %)" if match
                                                          else "")


def robots(doc) -> list[str]:
    out = ["## 11. Robots planned from their URDF", ""]
    if doc is None:
        return out + ["Not measured (run `make bench`).", ""]
    h = doc["header"]
    out += [provenance(doc), "",
            "`robots.py` (issue #37): each robot of the example-robot-data wheel drafted from "
            "its URDF (`gait_planner.model.urdf_import`) and planned as a user plans it, in "
            "fresh processes: *first build* the problem's build in a process whose compile "
            "cache (`$GAIT_PLANNER_CACHE`) is empty (the per-node derivative elements "
            "compiled with the C compiler; a refined grid compiles its new elements during "
            "the plan, in *first process*), *build* and the rest of the row from a second "
            "process with that cache filled (compiled) or from one process with CasADi's "
            "derivatives (casadi); *ready* the process's start to the built problem, imports "
            "and the draft included; *plan* the cold request (kinematic guess, refined while "
            "the continuous-dynamics certificate asks), *IPOPT* its solves over every grid; "
            "variables of the first grid, nodes of the plan. Cost of transport: "
            f"{h.get('cost_of_transport', 'W+ / (m g s)')}. Peak: the largest |effort| and "
            "the largest share of a joint's URDF effort limit (the joint named). Walked: "
            f"`gait-planner walk RUN.mcap --steps {h.get('steps', 10)} --json`, its half "
            "cycles or its error.", ""]
    rows = [dict(r, joints=f"{r.get('joints_planned', '–')} / {r.get('joints_locked', '–')}",
                 share=("–" if r.get("peak_torque_share") is None else
                        f"{r['peak_torque_share']:.1%} ({r['peak_share_joint']})"),
                 cert=_certificate(r.get("certificate", "")),
                 walked=(f"{r['half_cycles_walked']} of {h.get('steps', 10)}"
                         if r.get("half_cycles_walked") is not None else "–"),
                 why=r.get("walk") or r.get("error") or "")
            for r in doc["rows"] if r["kind"] == "robot"]
    out += table(rows, [
        ("robot", "robot", ""), ("derivatives", "mode", ""), ("joints planned / locked",
                                                                 "joints", ""),
        ("variables", "variables", ".0f"), ("nodes", "nodes", ".0f"),
        ("first build s", "first_build_s", ".1f"), ("first process s", "first_process_s", ".0f"),
        ("build s", "build_s", ".1f"), ("ready s", "ready_s", ".1f"), ("plan s", "plan_s", ".1f"),
        ("IPOPT s", "solve_s", ".1f"), ("iterations", "iterations", ".0f"),
        ("J (J s)", "cost", ".5g"), ("W+ J", "positive_work_J", ".3g"),
        ("W+/(m g s)", "cost_of_transport", ".3f"), ("peak N m", "peak_torque_Nm", ".3g"),
        ("peak / limit", "share", ""), ("certificate", "cert", ""),
        ("half cycles walked", "walked", ""), ("walk", "why", "")])
    out += [""]
    for robot in dict.fromkeys(r["robot"] for r in rows):  # computed: one plan or two?
        mine = [r for r in rows if r["robot"] == robot and r.get("success")]
        if len(mine) == 2:
            a, b = mine
            same = a["nodes"] == b["nodes"] and abs(a["cost"] - b["cost"]) <= 1e-6 * abs(a["cost"])
            out += [f"{robot}: the {a['mode']} and {b['mode']} rows " + (
                "reach the same plan." if same else
                f"are different plans ({a['nodes']} and {b['nodes']} nodes, J {a['cost']:.5g} "
                f"and {b['cost']:.5g} J s): round-off in the derivatives leads IPOPT to "
                "another local optimum or the certificate to another grid, so their times "
                "compare different work."), ""]
    walking = [dict(r, **r["posture"],
                    pitch="%.1f to %.1f" % tuple(r["posture"]["pelvis_pitch_deg"]),
                    roll="%.1f to %.1f" % tuple(r["posture"]["pelvis_roll_deg"]),
                    planned=_share(r["posture"], "planned"), locked=_share(r["posture"], "locked"))
               for r in rows if r.get("posture")]
    if walking:
        out += ["How each plan walks, read from its recording (`robot_posture.py`, issue #61): "
                "the base link's pitch and roll (/tf, deg), the knees' largest flexion from "
                "the zero pose with the leg on the ground (stance) and off it (swing), the "
                "step width (left minus right held points, m), every published effort's "
                "largest share of its URDF limit, planned and locked joints apart, and the "
                "largest impulse a locked joint takes at an impact (published apart, N m s).",
                ""]
        out += table(walking, [
            ("robot", "robot", ""), ("derivatives", "mode", ""), ("pelvis pitch deg", "pitch", ""),
            ("pelvis roll deg", "roll", ""), ("stance knee deg", "stance_knee_max_deg", ".1f"),
            ("swing knee deg", "swing_knee_max_deg", ".1f"), ("step width m", "step_width_m",
                                                               ".3f"),
            ("planned effort / limit", "planned", ""), ("locked effort / limit", "locked", ""),
            ("impulse N m s", "impulse_max_Nms", ".3g")]) + [""]
    twins = [dict(r, walked=(f"{r['half_cycles_walked']} of {h.get('steps', 10)}"
                             if r.get("half_cycles_walked") is not None else "–"),
                  why=r.get("walk") or r.get("error") or "")
             for r in doc["rows"] if r["kind"] == "counterpart"]
    if twins:
        out += ["The robot beside its human counterpart: walker3d with its lengths scaled to "
                "the robot's leg length (hip to sole) and its masses to the robot's total mass "
                "(inertias by mass x length^2), step and time step scaled as the importer "
                "scales them (`scaled_walker.py`), and walker3d itself; each compiled, "
                "planned cold in a fresh process.", ""]
        out += table(twins, [
            ("plan", "label", ""), ("leg m", "leg_length_m", ".4f"), ("mass kg", "mass_kg", ".2f"),
            ("step m", "step_length_m", ".4f"), ("half cycle s", "duration_s", ".3f"),
            ("speed m/s", "speed_m_s", ".2f"), ("J (J s)", "cost", ".5g"),
            ("W+ J", "positive_work_J", ".3g"), ("W+/(m g s)", "cost_of_transport", ".3f"),
            ("peak N m", "peak_torque_Nm", ".3g"), ("iterations", "iterations", ".0f"),
            ("nodes", "nodes", ".0f"), ("plan s", "plan_s", ".1f"),
            ("half cycles walked", "walked", ""), ("walk", "why", "")]) + [""]
    if h.get("figure"):
        out += [f"Each robot at the mid-step node of its plan, its own meshes placed by the "
                f"recording's /tf as rerun draws them (`robot_picture.py`): "
                f"[{h['figure']}]({h['figure']})", "",
                f"![robots mid-step]({h['figure']})", ""]
    return out


def _share(posture: dict, kind: str) -> str:
    """'87.1% (waist_roll_joint)' of robot_posture's largest share of one kind, or '–'."""
    share = posture.get(f"effort_share_{kind}")
    return "–" if share is None else f"{share:.1%} ({posture[f'effort_share_{kind}_joint']})"


def _request_rows(doc) -> list[dict]:
    """any_request.py's rows with their ground, speed, step, mu and outcome in words."""
    return [dict(r, ground=("slope %g°" % r["request"]["slope"] if "slope" in r["request"]
                            else "stairs %+g m" % r["request"]["step_height"]
                            if "step_height" in r["request"] else "level"),
                 speed=r["request"].get("speed", "free"), step=r["request"]["step_length"],
                 mu=r["request"]["friction_coefficient"],
                 outcome=("refused" if "refused" in r else
                          "certified" if r["certified"] else
                          "converged, not certified" if r["success"] else "failed"),
                 start=_start_word(r))
            for r in doc["rows"]]


def _start_word(row: dict) -> str:
    """Where an answer started, in a word: a gait library, a path of parameters from the
    warm-start store or this process, a warm re-plan, or cold (first, or after a failed
    path)."""
    if row.get("library", "").startswith("started from"):
        return "library"
    start = row.get("start", "")
    if "refused" in row or not start:
        return "cold" if "refused" not in row else "–"
    if start.startswith("refined"):
        return "refined"
    if "along a parameter path" in start:
        return "path, then cold" if "failed after" in start.split(";")[0] else "path"
    return "warm" if start.startswith("warm") else "cold"


def any_request_library(doc) -> list[str]:
    """Section 12's rows answered with a gait library (`any_request.py --library`)."""
    if doc is None:
        return ["From a gait library: not measured (`any_request.py --library FOLDER`).", ""]
    h, t = doc["header"], doc["header"]["totals"]
    median = t.get("library_median_s")
    out = [provenance(doc), "",
           f"From a gait library: the same requests, answered by a process serving the "
           f"walker3d library `{h.get('library_grid') or Path(h['library']).name}` (a grid "
           "of plans over the free-speed walk's fields, `gait-planner library build`) as "
           "the node's parameter gait_library does: a request inside its grid starts from "
           "its neighbours (a seed whose attempts fail is planned cold), every other one is "
           f"planned cold as above. {t['from_library']} of the "
           f"{t['requests'] - t['refused']} answered requests were inside it"
           + (f", answered in a median {median:.3f} s" if median is not None else "")
           + f"; all answers: median {t['median_s']:.2f} s, p95 {t['p95_s']:.1f} s.", ""]
    out += table(_request_rows(doc), [
        ("ground", "ground", ""), ("speed m/s", "speed", ""), ("step m", "step", ""),
        ("mu", "mu", ""), ("start", "start", ""), ("outcome", "outcome", ""),
        ("iterations", "iterations", ".0f"), ("answer s", "answer_s", ".2f")])
    return out + [""]


def _totals_row(label: str, t: dict) -> str:
    return (f"| {label} | {t['requests']} | {t['refused']} | {t['compilations']} | "
            f"{t['converged']} | {t['certified']} | {t['median_s']:.2f} | {t['p95_s']:.1f} | "
            f"{t['max_s']:.1f} | {t['median_iterations']:.0f} |")


def any_request(doc, cold_doc=None, library_doc=None) -> list[str]:
    out = ["## 12. Any request without compiling", ""]
    if doc is None:
        return out + ["Not measured (run `make bench`).", ""]
    h, t = doc["header"], doc["header"]["totals"]
    store = h.get("start") == "warm-start store"
    out += [provenance(doc), "",
            f"`any_request.py` (issue #39): one fresh process after `make setup` answers "
            f"{t['requests']} requests drawn at random (seed {h['seed']}) across "
            f"{h['scene']}'s ranges (a third each level, ramp within ±10°, stairs within "
            f"±0.15 m; half at a speed within 0.8-1.6 m/s; friction 0.4-1.2, step 0.4-0.9 m), "
            + ("each from a copy of the warm-start store `make setup` leaves (the default "
               "plan and the scene's warm-start anchors) along a path of parameters from the "
               "nearest plan kept (`gait_planner/parameter_path.py`; planned cold if the "
               "path fails), " if store else "each cold, ")
            + f"and certified as the node certifies it (refined grids included), "
            f"{h['time_limit_s']:g} s per request. A request whose speed its step cannot "
            "reach within the scene's durations is refused before planning, with the "
            "reachable range.", "",
            "| start | requests | refused | compilations | converged | certified | median s "
            "| p95 s | max s | median iterations |", "|---|---|---|---|---|---|---|---|---|---|",
            _totals_row("warm-start store, paths" if store else "cold", t)]
    if cold_doc is not None:
        out.append(_totals_row(f"cold ({cold_doc['header']['date_utc'][:16]} UTC)",
                               cold_doc["header"]["totals"]))
    out.append("")
    out += table(_request_rows(doc), [
        ("ground", "ground", ""), ("speed m/s", "speed", ""), ("step m", "step", ""),
        ("mu", "mu", ""), ("start", "start", ""), ("outcome", "outcome", ""),
        ("iterations", "iterations", ".0f"), ("answer s", "answer_s", ".2f"),
        ("compiled", "compiled", "")])
    return out + [""] + any_request_library(library_doc)


def replan_walk(docs: list[dict]) -> list[str]:
    out = ["## 13. Walking by re-planning", ""]
    if not docs:
        return out + ["Not measured.", ""]
    out += ["`replan_walk.py` (issue #63, `gait_planner.walk.replan`): each scene walked in "
            "MuJoCo with the reference controller (config/walk.yaml), from standing (or moving, "
            "at the gait's first node, where marked), a number of half cycles, then a stop and "
            "2 s standing; *re-planned*: a transition from the walker's measured state at "
            "every strike (two half cycles onto the gait; its solver stopped after the limit "
            "in the table, 0.75 of the gait's half cycle by default), each solve's wall time on this machine charged to the "
            "simulated clock (the walker keeps its plan until the new one arrives); *one "
            "plan*: the start plan carries every half cycle, only the stop is planned during "
            "the walk. The stop is planned two strikes ahead from the plan's own state there. "
            "Wall times (and so when plans take over) depend on the machine's load: two runs "
            "differ. Feedback share: RMS feedback / RMS planned effort over the whole walk "
            "(start, walk, stop, standing). Request: the scene's default, or one of "
            "walker3d's hard requests (`hard_cases.py`, `--cases`; a 300 s limit for its gait "
            "and for the start).", ""]
    for doc in docs:
        rows = [dict(r, walked=f"{r['half_cycles_walked']} of {doc['header']['half_cycles']}",
                     deadline=r.get("deadline", 0.75),  # the default before it was a row's
                     model_error=r.get("model_error", "none"),
                     case=r.get("case", "default"),
                     replans=(f"{r['replans_converged']} of {r['replans']}"
                              if r["replans"] else "–"))
                for r in doc["rows"]]
        out += [provenance(doc), ""] + _completed(rows, doc["header"]) + table(rows, [
            ("scene", "scene", ""), ("request", "case", ""), ("start", "start", ""),
            ("mode", "mode", ""), ("re-plan limit (half cycles)", "deadline", ".2f"),
            ("half cycles walked", "walked", ""), ("stood at the end", "stood", ""),
            ("re-plans converged", "replans", ""),
            ("median iterations", "replan_iterations_median", ".0f"),
            ("median wall s", "replan_wall_median_s", ".2f"),
            ("feedback share", "feedback_share", ".0%"), ("unplanned touches", "touches", ""),
            ("why it ended", "stopped", ""), ("model error", "model_error", "")]) + [""]
    return out


def _completed(rows: list[dict], header: dict) -> list[str]:
    """Under model error (several walks a row): how many walks of each scene and mode
    completed (walked every half cycle asked, stopped and stood)."""
    if not header.get("model_error_seeds"):
        return []
    counts: dict[tuple, list] = {}
    for r in rows:
        done = r["stood"] and r["half_cycles_walked"] >= header["half_cycles"]
        counts.setdefault((r["scene"], r["mode"]), []).append(done)
    return ["Complete under every model error at once: " + "; ".join(
        f"{scene} {mode} {sum(d)} of {len(d)}" for (scene, mode), d in counts.items())
        + ".", ""]


def main() -> None:
    docs = {name: load_results(name) for name in ("work_precision", "integrators", "model_size",
                                         "model_size_compiled", "hard_cases", "cold_solve",
                                         "node_latency_walker3d", "request_sweep", "walk",
                                         "gait_trends", "gait_library", "robots",
                                         "any_request", "any_request_cold",
                                         "any_request_library",
                                         "model_error", "smoothness")}
    lines = ["# Benchmark report", "",
             "Written by `make bench` (`benchmarks/bench.py`, then `benchmarks/report.py`) from "
             "`benchmarks/results/*.json`; every number below is in those files with the "
             "machine, date and commit it was measured at. Wall times on this 2-core machine "
             "vary by ±10 % between runs (more under load: see each section's load figure); "
             "iteration counts, errors and costs are reproducible. Dated notes of earlier "
             "changes are in [HISTORY.md](HISTORY.md).", ""]
    lines += work_precision(docs["work_precision"])
    lines += integrators(docs["integrators"])
    lines += model_size(docs["model_size_compiled"] or docs["model_size"])
    lines += hard_cases(docs["hard_cases"])
    lines += speed(docs["cold_solve"], docs["node_latency_walker3d"])
    lines += request_sweep(docs["request_sweep"])
    lines += walk(docs["walk"])
    lines += model_error(docs["model_error"])
    lines += smoothness(docs["smoothness"])
    lines += gait_trends(docs["gait_trends"])
    lines += gait_library(docs["gait_library"])
    lines += peers({scene: doc for scene in ("walker2d", "walker3d")
                    if (doc := load_results(f"peers_{scene}"))})
    lines += robots(docs["robots"])
    lines += any_request(docs["any_request"], docs["any_request_cold"],
                         docs["any_request_library"])
    lines += replan_walk([doc for name in ("replan_walk", "replan_walk_walker3d",
                                          "replan_walk_walker3d_deadline2", "replan_walk_20",
                                          "replan_walk_model_error",
                                          "replan_walk_hard_deadline2",
                                          "replan_walk_hard_moving",
                                          "replan_walk_stairs_down")
                          if (doc := load_results(name))])
    out = (RESULTS if OTHER else HERE) / "REPORT.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
