"""The transcription's path rows (docs/design.md section 8): what a plan must keep at its
nodes and intervals beyond the dynamics, the contacts and the cones. Per phase, the swing
points' clearance above the ground and their speed before a strike (`ocp.clearance`), the
joint ranges and speed limits, the torso's lean and height (`ocp.posture`), the legs'
clearance from each other (`ocp.legs`); and the
per-node rows element that evaluates a node's contact-dependent rows (cones, unilateral
conditions, the entries bounded at a node) from its own unknowns.

`PathRows` is a part of `ocp.transcription.Transcription` (a mixin: it reads the
transcription's unknowns, parameters and groups, and adds its rows to them); the rows are
declared here, assembled there.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from gait_planner.model.ground import PARAMETERS
from gait_planner.ocp.clearance import (approach_schedule, clearance_rows,
                                        clearance_schedule, ground_heights, midpoint_heights,
                                        schedule_heights, segment_heights, segment_schedule,
                                        strike_rows, strike_schedule)
from gait_planner.ocp.elements import ElementGroup
from gait_planner.ocp.legs import SMOOTHING, leg_clearance_rows
from gait_planner.ocp.posture import (JOINT_RANGE_ROW_UPPER, joint_limit_constants,
                                      joint_limit_rows, joint_speed_margins,
                                      joint_speeds_margins)
from gait_planner.ocp.settings import joint_speed_bounds

FORCE_SCALE = 1000.0  # N: contact multipliers are unknowns in these units


class PathRows:
    """The path rows of a `Transcription` (its `_path` and `_node_rows` steps)."""

    def _path(self):
        mb, N, s = self.mb, self.N, self.settings
        held = [{p for bc in self.contacts[k] for p in bc.points}
                for k in self.phase_of_interval[: N - 1]]  # interval N-1: the image of 0
        schedule = clearance_schedule(mb.scene, held, s, s.base_time_step)
        ground, self.clearances = clearance_rows(mb, lambda n: self.Q[:, n], schedule,
                                                 s.foot_half_width, self.gs, (self.ground_p,))
        if ground:
            first_row = sum(int(e.shape[0]) for _, e in self._eq + self._ineq)
            self._clearance_elements(schedule, first_row)
            self._ineq.append(("ground_clearance", ca.vertcat(*ground)))
            self._without_elements["ground_clearance"] = ca.MX(-ca.DM(self.clearances))
        last = {p for bc in self.contacts[self.phase_of_interval[N - 1]] for p in bc.points} \
            if self.transition else None  # the joined gait's, or standing still
        strikes = strike_schedule(mb.scene, held, last) if s.strike_speed_max > 0 else {}
        if strikes:
            c = np.array([s.base_time_step, s.strike_speed_max])
            rows = self._interval_groups(
                strikes, lambda points: strike_rows(mb, points, self.gs),
                dict.fromkeys(strikes, c),
                sum(int(e.shape[0]) for _, e in self._eq + self._ineq))
            self._ineq.append(("strike_speed", rows))
            self._without_elements["strike_speed"] = ca.MX(rows.shape[0], 1)
        approach = approach_schedule(strikes, held) if s.strike_deceleration_max > 0 else {}
        if approach:  # the same rows j intervals before the strike, a bound growing with j
            first = sum(int(e.shape[0]) for _, e in self._eq + self._ineq)
            rows = []
            for j, schedule in approach.items():
                bound = s.strike_speed_max + s.strike_deceleration_max * j * s.base_time_step
                rows.append(self._interval_groups(
                    schedule, lambda points: strike_rows(mb, points, self.gs),
                    dict.fromkeys(schedule, np.array([s.base_time_step, bound])),
                    first + sum(int(r.shape[0]) for r in rows)))
            rows = ca.vertcat(*rows)
            self._ineq.append(("strike_approach", rows))
            self._without_elements["strike_approach"] = ca.MX(rows.shape[0], 1)
        segments = (segment_schedule(mb.scene, held, self.gs, schedule)
                    if s.ground_clearance else {})
        if segments:  # stairs down: segment rows, or midpoint rows with the edge margin
            exact = self.gs.segment_rows
            rows = self._interval_groups(
                {n: points for n, (points, _) in segments.items()},
                lambda points: (segment_heights if exact else midpoint_heights)(
                    mb, points, s.foot_half_width, self.gs),
                {n: np.array([s.base_time_step, required]) if exact else np.zeros(2)
                 for n, (_, required) in segments.items()},
                sum(int(e.shape[0]) for _, e in self._eq + self._ineq))
            name = "segment_clearance" if exact else "midpoint_clearance"
            self._ineq.append((name, rows))
            self._without_elements[name] = ca.MX(rows.shape[0], 1)
        root = mb.block(mb.scene.root.body).start
        inner = self.Q[:, 1:N]
        for name, entry, bound in (("torso_lean", self._uprightness(inner), self._lean_bound),
                                   ("torso_height", inner[root + 2, :], s.torso_height_min)):
            if bound > 0:  # the entry itself is in _node_rows
                self._ineq.append((name, ca.vec(entry - bound)))
                self._without_elements[name] = ca.MX(ca.DM.ones(N - 1) * -bound)
        phase_index = {p.name: k for k, p in enumerate(mb.scene.gait.phases)}
        ranges = [("joint_limits", "joint_limits", list(range(1, N)), s.joint_limits)] + [
            (f"joint_limits[{phase}]", f"joint_limits_phase{phase_index[phase]}",
             [n for n in range(1, N) if self.phase_of_interval[n] == phase_index[phase]],
             limits) for phase, limits in s.phase_joint_limits]
        for name, function_name, nodes, limits in ranges:
            if nodes and limits:
                first_row = sum(int(e.shape[0]) for _, e in self._eq + self._ineq)
                rows = self._node_terms(
                    joint_limit_rows(mb, tuple(a for a, _, _ in limits), function_name),
                    joint_limit_constants(mb, limits), first_row, nodes)
                self._ineq.append((name, ca.vec(rows)))
                self._without_elements[name] = ca.MX(rows.numel(), 1)
                self._upper[name] = JOINT_RANGE_ROW_UPPER
        speeds = joint_speed_bounds(mb.scene, s)  # deg/s per joint, 0 = none
        if any(w > 0 for w in speeds):
            first_row = sum(int(e.shape[0]) for _, e in self._eq + self._ineq)
            if len(set(speeds)) == 1:  # one bound: the function every scene shares
                speed = self._interval_terms(joint_speed_margins(mb),
                                             math.radians(speeds[0]), first_row)
            else:  # a bound per joint (joint_speed_limits), unbounded joints left out
                bounded = [(j.name, w) for j, w in zip(mb.scene.joints, speeds) if w > 0]
                speed = self._interval_terms(
                    joint_speeds_margins(mb, tuple(n for n, _ in bounded)),
                    np.radians([w for _, w in bounded]), first_row)
            self._ineq.append(("joint_speed", ca.vec(speed)))
            self._without_elements["joint_speed"] = ca.MX(speed.numel(), 1)
        legs = leg_clearance_rows(mb) if s.legs_apart else None
        if legs is not None:  # nodes N-1 and N: images of 0 and 1, their rows mirrored
            first_row = sum(int(e.shape[0]) for _, e in self._eq + self._ineq)
            rows = self._node_terms(legs, np.array([s.leg_clearance, SMOOTHING]), first_row,
                                    list(range(1, N)))
            self._ineq.append(("leg_clearance", ca.vec(rows)))
            self._without_elements["leg_clearance"] = ca.MX(rows.numel(), 1)

    def _uprightness(self, q):
        """The z component of the root's up axis in configurations q (k, n) (row (1, n)):
        its d3, or for a scene drafted from a URDF its link frame's z axis (G1's pelvis
        frame is pitched 3.1 deg from its principal axes, the directors)."""
        scene = self.mb.scene
        root = self.mb.block(scene.root.body).start
        if scene.robot is None:
            return q[root + 11, :]
        up = scene.robot.link_pose(scene.root.body)[1][:, 2]  # director components
        return up[0] * q[root + 5, :] + up[1] * q[root + 8, :] + up[2] * q[root + 11, :]

    @property
    def _lean_bound(self) -> float:
        """The up axis' z component at the torso's largest lean (0: no lean limit)."""
        lean_max = self.settings.torso_lean_max
        return float(np.cos(np.radians(lean_max))) if lean_max > 0 else 0.0

    def _clearance_elements(self, schedule: dict[int, dict[str, float]], first_row: int):
        """The swing points' heights of the ground_clearance rows (`clearance_rows`, from
        row first_row of g on) declared as node elements, one Function per set of swing
        points (the required heights are the rows' constant parts)."""
        nodes: dict[tuple[tuple[str, ...], bool], list[tuple[int, np.ndarray]]] = {}
        row = first_row
        half_width = self.settings.foot_half_width
        for n, points in schedule.items():
            if points:
                size = len(schedule_heights(self.mb, points, half_width))
                nodes.setdefault((tuple(points), self.layout.mirrored(n == self.N - 1)), []).append(
                    (n, row + np.arange(size)))
                row += size
        q, c, ground = ca.SX.sym("q", self.mb.k), ca.SX.sym("c", 1), self.gs.values
        for (points, mirrored), chosen in nodes.items():
            heights = ground_heights(self.mb, points, half_width, self.gs)
            fn = ca.Function("clearance_" + "_".join(points), [q, c, ground],
                             [heights(q, ground)], ["q", "c", "ground"], ["z"])
            self.elements.append(ElementGroup(
                self.layout.node_element(fn, mirrored),
                np.stack([self.layout.u_index(n) for n, _ in chosen], 1),
                np.stack([self.layout.node_p_index(n) for n, _ in chosen], 1),
                np.stack([rows for _, rows in chosen], 1), np.zeros(1)))

    def _interval_groups(self, schedule: dict[int, tuple[str, ...]], rows_of,
                         constants: dict[int, np.ndarray], first_row: int) -> ca.MX:
        """Rows rows_of(points)(q_n, q_{n+1}, h_n, c_n) of the intervals n of `schedule`
        ({interval: points}: the strike_speed rows of `strike_schedule`, the
        segment_clearance rows of `segment_schedule`; constants {interval: c_n (2,)}), from
        row first_row of g on, declared as interval elements, one Function per set of
        points and one group per Function and constant; returns them as one MX column."""
        groups: dict[tuple[tuple[str, ...], bool, tuple[float, ...]],
                     list[tuple[int, np.ndarray]]] = {}
        functions: dict[tuple[str, ...], ca.Function] = {}
        out, row = [], first_row
        for n, points in schedule.items():
            fn = functions.setdefault(points, rows_of(points))
            size = int(fn.size1_out(0))
            c = tuple(float(v) for v in constants[n])
            groups.setdefault((points, self.layout.mirrored(n == self.N - 2), c), []).append(
                (n, row + np.arange(size)))
            row += size
            out.append(fn(self.Q[:, n], self.Q[:, n + 1], self.h[n], ca.DM(c),
                          *([self.ground_p] if fn.n_in() == 5 else [])))
        for (points, next_mirrored, c), chosen in groups.items():
            self.elements.append(ElementGroup(
                self.layout.interval_element(functions[points], next_mirrored),
                np.stack([self.layout.interval_z_index(n) for n, _ in chosen], 1),
                np.stack([self.layout.interval_p_index(n) for n, _ in chosen], 1),
                np.stack([rows for _, rows in chosen], 1), np.array(c)))
        return ca.vertcat(*out)

    def _node_rows(self):
        """Declares, at each node 1..N-1 (a transition's from node 0), the rows that depend
        on its configuration and contact multipliers alone as node elements
        (`_node_rows_element`): the contact term of its dynamics rows (a transition's node
        0: of its start_momentum rows), its friction cones and its torso lean and height
        (their entries of q; the bounds are the rows' constant parts; not at a
        transition's given node 0)."""
        N, nd = self.N, self.mb.ndof
        first, row = {}, 0
        for name, e in self._eq + self._ineq:
            first[name], row = row, row + int(e.shape[0])
        cone_row = first.get("friction_cone", 0)
        nodes: dict[tuple[int, bool, bool], list[tuple[int, np.ndarray]]] = {}
        for n in range(0 if self.transition else 1, N):
            k = int(self.phase_of_interval[n])
            rows = []
            if self.rows[k].shape[0]:
                if n == 0:
                    rows += list(first["start_momentum"] + np.arange(nd))
                else:
                    j = [m for m in range(1, N) if self.phase_of_interval[m] == k].index(n)
                    rows += list(first[f"dynamics[{self._phase_name(k)}]"] + j * nd
                                 + np.arange(nd))
                cones = sum(len(bc.points) + (2 if bc.full and not bc.planar else 0)
                            for bc in self.contacts[k])
                rows += list(cone_row + np.arange(cones))
                cone_row += cones
            posture = n > 0
            if posture:
                rows += [first[name] + n - 1 for name in ("torso_lean", "torso_height")
                         if name in first]
            if rows:
                nodes.setdefault((k, self.layout.mirrored(n == N - 1), posture), []).append(
                    (n, np.array(rows)))
        for (k, mirrored, posture), chosen in nodes.items():
            self.elements.append(ElementGroup(
                self._node_rows_element(k, mirrored, posture),
                np.stack([np.concatenate([self.layout.u_index(n), self.layout.lam_index(n)])
                          for n, _ in chosen], 1),
                np.stack([np.append(self.layout.node_p_index(n), self.layout.mu_index)
                          for n, _ in chosen], 1),
                np.stack([rows for _, rows in chosen], 1), np.array(self._cone_constants)))

    def _node_rows_element(self, k: int, mirrored: bool, posture: bool = True) -> ca.Function:
        """`_node_rows` of a node of phase k as an SX Function of z = (u_n, lambda_n),
        pz = (qref_n, step length, ground, mu) and c = `_cone_constants`: the contact term
        P(q_n)^T C^T lambda_n / FORCE_SCALE (ndof,) if the phase holds contacts, the
        friction cones, then (with posture) the torso's d3_z and height if they are
        limited."""
        mb, s, nd, kq, G = self.mb, self.settings, self.mb.ndof, self.mb.k, len(PARAMETERS)
        contacts = self.contacts[k]
        z = ca.SX.sym("z", nd + sum(bc.n_multipliers for bc in contacts))
        pz, c = ca.SX.sym("pz", kq + 2 + G), ca.SX.sym("c", 2)
        ground, mu = self.gs.like(pz[kq + 1 : kq + 1 + G]), pz[kq + 1 + G]
        q = mb.reparametrise(z[0:nd], pz[0:kq])
        if mirrored:
            q = self.layout.image(q, pz[kq], ground.values)
        lam, held, cones, offset = FORCE_SCALE * z[nd:], [], [], 0
        for bc in contacts:
            part = lam[offset : offset + bc.n_multipliers]
            held.append(part[0 : bc.n_rows])
            cones += bc.cone_rows(part, q, mu, c[0], c[1], normal=ground.normal)
            offset += bc.n_multipliers
        C = self.rows_of[k](ground.values)
        out = [mb.null_space_transpose(q, ca.mtimes(C.T, ca.vertcat(*held)))
               / FORCE_SCALE] + cones if contacts else []
        root = mb.block(mb.scene.root.body).start
        out += [self._uprightness(q)] if self._lean_bound > 0 and posture else []
        out += [q[root + 2]] if s.torso_height_min > 0 and posture else []
        name = f"node_rows_phase{k}" + ("_mirrored" if mirrored else "") + \
            ("" if posture else "_contacts")
        return ca.Function(name, [z, pz, c], [ca.vertcat(*out)], ["z", "pz", "c"], ["r"])
