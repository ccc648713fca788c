"""A time-varying LQR walking the plans, beside the shipped controller (issue #40 item 1):
a baseline from the field's usual way to stabilise an optimised trajectory, not a product
controller.

    .venv/bin/python benchmarks/walk.py --plans DIR          # make and keep the plans
    .venv/bin/python benchmarks/lqr_walk.py DIR/plan_*.mcap  # walk them with the LQR
    .venv/bin/python benchmarks/lqr_walk.py PLAN.mcap --r 5 --steps 4

The walker is `gait-planner walk`'s (`walk.walk_plan.walk_model` with config/walk.yaml:
0.5 ms steps, the joints' damping, the no-slip passes), started on the plan's node 0. The
reference state at the plan's time tau: the plan's configuration in MuJoCo's coordinates
(`plan_qpos`), its joint rates and the root's velocity (`plan_root_qvel`; at tau = 0 the
walk's root rates); the feed-forward the plan's efforts plus kd times the planned rates
(MuJoCo's damping at the reference). MuJoCo's transition is linearised by finite
differences every `block` steps along the joined half cycles, each column by the one-sided
difference that does not cross a contact switch, at the reference lowered `sink` m into the
ground (held spheres exactly on the ground are on the knife edge of contact detection: a
1e-6 perturbation rolls a foot onto one sphere or the other, and A reached 1e11). A block's
transition is the step's composed `block` times (zero-order hold); the Riccati recursion
runs backward over the whole walk with Q = diag(1/q_joint^2 on the joint angles, 1/q_root^2
on the root's position and orientation, 1/v^2 on every velocity) and R = 1/r^2, both times
the block's length; the feedback -K dx is held over each block. The plan's time is paced as
the walk paces it (`walk.clock.PlanClock`, gain --clock-gain). The walk stops by the
walk's own rules (`walk.walk_plan.stop_reason`, config/walk.yaml `stop`); feedback share =
RMS of everything beyond the plan's efforts over RMS of the plan's efforts, as `gait-planner
walk` reports it; --torque-scale 0 or 0.5 walks with the plan's efforts scaled, the walk's
self-test (the gains stay those designed about the full efforts). Results and their
dates: benchmarks/HISTORY.md (2026-11-30, night).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np


class Linearised:
    """The walker of `path` and its reference, linearised about the plan (module docstring)."""

    def __init__(self, path: Path, steps: int, block: int, sink: float):
        import mujoco

        from gait_planner.io.mcap_reader import read_plan_mcap
        from gait_planner.walk.reference import Reference, planned_joints
        from gait_planner.walk.walk_plan import load_config, walk_model

        self.cfg = load_config()
        rec = planned_joints(read_plan_mcap(path))
        self.ref = Reference.from_recording(rec, steps)
        self.joint_names = rec.joint_names
        self.kd = self.cfg["joints"]["kd"]
        self.wm = walk_model(rec, self.ref.scene, self.cfg)
        self.m, self.block, self.sink = self.wm.model, block, sink
        self.d = mujoco.MjData(self.m)
        self.h = self.m.opt.timestep
        self.nv, self.nu = self.m.nv, len(self.wm.dof)
        self.i_root = self.ref.scene.body_index(self.ref.scene.root.body)

    def reference(self, tau: float, scale: float = 1.0
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(qpos, qvel, u, plan efforts) at the plan's time tau; u = scale x efforts + kd
        rates (scale: the self-test's factor on the plan's efforts)."""
        from gait_planner.walk.mujoco_model import plan_qpos, plan_root_qvel

        ref, h = self.ref, self.h
        angles, rates, efforts, _ = ref.at(tau)
        D = ref.root_at(tau)[1]
        root = (plan_root_qvel(self.wm, D, *ref.root_rate0) if tau < h else
                plan_root_qvel(self.wm, D, ref.root_velocity_at(tau, h),
                               ref.root_rate_at(tau, h)))
        qvel = np.zeros(self.nv)
        qvel[:len(root)], qvel[self.wm.dof] = root, rates
        return (plan_qpos(self.wm, self.i_root, ref.q_at(tau), angles), qvel,
                scale * efforts + self.kd * rates, efforts)

    def difference(self, qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
        """qb - qa in the tangent space (nv,)."""
        import mujoco

        out = np.zeros(self.nv)
        mujoco.mj_differentiatePos(self.m, out, 1.0, qa, qb)
        return out

    def _step(self, qpos, qvel, u, warm) -> tuple[np.ndarray, np.ndarray]:
        import mujoco

        d = self.d
        d.qpos[:], d.qvel[:], d.qacc_warmstart[:] = qpos, qvel, warm
        d.qfrc_applied[:] = 0.0
        d.qfrc_applied[self.wm.dof] = u
        mujoco.mj_step(self.m, d)
        return d.qpos.copy(), d.qvel.copy()

    def transition(self, tau: float, eps: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
        """(A (2nv, 2nv), B (2nv, nu)) of one simulation step at the (sunk) reference."""
        import mujoco

        qpos, qvel, u, _ = self.reference(tau)
        qpos = qpos.copy()
        qpos[1 if self.wm.planar else 2] -= self.sink
        d = self.d
        d.qpos[:], d.qvel[:] = qpos, qvel
        d.qfrc_applied[:] = 0.0
        d.qfrc_applied[self.wm.dof] = u
        mujoco.mj_forward(self.m, d)
        warm = d.qacc.copy()
        q0, v0 = self._step(qpos, qvel, u, warm)

        def column(plus, minus, e):  # the side that does not cross a contact switch
            up = np.r_[self.difference(q0, plus[0]), plus[1] - v0] / e
            down = -np.r_[self.difference(q0, minus[0]), minus[1] - v0] / e
            return up if np.abs(up).max() < np.abs(down).max() else down

        A, B = np.zeros((2 * self.nv, 2 * self.nv)), np.zeros((2 * self.nv, self.nu))
        for i in range(self.nv):
            dq = np.zeros(self.nv)
            dq[i] = eps
            qp, qm = qpos.copy(), qpos.copy()
            mujoco.mj_integratePos(self.m, qp, dq, 1.0)
            mujoco.mj_integratePos(self.m, qm, -dq, 1.0)
            A[:, i] = column(self._step(qp, qvel, u, warm), self._step(qm, qvel, u, warm), eps)
            A[:, self.nv + i] = column(self._step(qpos, qvel + dq, u, warm),
                                       self._step(qpos, qvel - dq, u, warm), eps)
        for j in range(self.nu):
            du = np.zeros(self.nu)
            du[j] = 1e3 * eps
            B[:, j] = column(self._step(qpos, qvel, u + du, warm),
                             self._step(qpos, qvel, u - du, warm), 1e3 * eps)
        return A, B

    def gains(self, q_joint: float, q_root: float, v: float, r: float) -> list[np.ndarray]:
        """K (nu, 2nv) per block of the walk, by the backward Riccati recursion."""
        dt = self.block * self.h
        count = int(math.ceil(self.ref.steps * self.ref.period / dt)) + 1
        blocks = []
        for k in range(count):
            A, B = self.transition(k * dt)
            Ab, Bb = np.eye(2 * self.nv), np.zeros((2 * self.nv, self.nu))
            for _ in range(self.block):
                Ab, Bb = A @ Ab, A @ Bb + B
            blocks.append((Ab, Bb))
        weights = np.full(2 * self.nv, 1.0 / v**2)
        weights[np.setdiff1d(np.arange(self.nv), self.wm.dof)] = 1.0 / q_root**2
        weights[self.wm.dof] = 1.0 / q_joint**2
        Q, R = np.diag(weights) * dt, np.eye(self.nu) * dt / r**2
        P, out = 10.0 * Q, [None] * count
        for k in reversed(range(count)):
            A, B = blocks[k]
            K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
            P = Q + A.T @ P @ (A - B @ K)
            out[k] = K
            P = 0.5 * (P + P.T)
        return out


def walk_lqr(path: Path, steps: int, args) -> dict:
    """Walk `path` with the LQR: half cycles, why it stopped, feedback share, times."""
    import mujoco

    from gait_planner.walk.clock import PlanClock
    from gait_planner.walk.walk_plan import stop_reason

    start = time.perf_counter()
    lin = Linearised(path, steps, args.block, args.sink)
    K = lin.gains(args.q_joint, args.q_root, args.v, args.r)
    design = time.perf_counter() - start
    m, d, ref, wm, h, stop = lin.m, mujoco.MjData(lin.m), lin.ref, lin.wm, lin.h, lin.cfg["stop"]
    qpos, qvel, _, _ = lin.reference(0.0)
    d.qpos[:], d.qvel[:] = qpos, qvel
    clock = PlanClock(args.clock_gain, lin.cfg["clock"]["rate_min"], lin.cfg["clock"]["rate_max"])
    speed, root = ref.step_length / ref.period, m.body(wm.root).id
    end, reason, extra, plan, fb, steps_done = steps * ref.period, "completed", [], [], None, 0
    while clock(d.time) < end - 0.5 * h:
        tau = clock(d.time)
        q_ref, v_ref, u, efforts = lin.reference(tau, args.torque_scale)
        if steps_done % lin.block == 0:
            dx = np.r_[lin.difference(q_ref, d.qpos), d.qvel - v_ref]
            fb = -K[min(int(tau / (lin.block * h)), len(K) - 1)] @ dx
        d.qfrc_applied[:] = 0.0
        d.qfrc_applied[wm.dof] = u + fb
        # beyond the plan's efforts: the LQR's and the damping's difference from the plan's
        extra.append(u + fb - lin.kd * d.qvel[wm.dof] - efforts)
        plan.append(efforts)
        mujoco.mj_step(m, d)
        steps_done += 1
        clock.pace(h, float(d.subtree_com[root][0] - ref.com_at(tau)[0]), speed)
        com, (phi, D) = d.site_xpos[wm.root_site], ref.root_at(clock(d.time))
        tilt = math.degrees(math.acos(np.clip(
            d.site_xmat[wm.root_site].reshape(3, 3)[:, 2] @ D[:, 2], -1.0, 1.0)))
        reason = stop_reason(stop, d, com[2], phi[2], tilt,
                             ref.at(clock(d.time))[0] - d.qpos[wm.qpos], lin.joint_names, d.time)
        if reason != "completed":
            break
    rms = lambda x: float(np.sqrt(np.mean(np.square(x))))  # noqa: E731
    walked = steps if reason == "completed" else int(clock(d.time) / ref.period)
    return {"half_cycles_walked": walked, "stopped": reason,
            "feedback_share": rms(extra) / max(rms(plan), 1e-12), "design_s": design,
            "walk_s": time.perf_counter() - start - design}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("plans", type=Path, nargs="+", help="plan recordings (MCAP)")
    parser.add_argument("--steps", type=int, default=10, help="half cycles to walk")
    parser.add_argument("--r", type=float, default=10.0, help="N m: R = 1/r^2")
    parser.add_argument("--v", type=float, default=2.0, help="rad/s and m/s: velocity weight")
    parser.add_argument("--q-joint", type=float, default=0.03, help="rad: joint angle weight")
    parser.add_argument("--q-root", type=float, default=0.02, help="m and rad: root weight")
    parser.add_argument("--block", type=int, default=4, help="simulation steps per gain")
    parser.add_argument("--sink", type=float, default=5e-4, help="m: reference lowered by")
    parser.add_argument("--clock-gain", type=float, default=1.0, help="1/s: the plan's pace")
    parser.add_argument("--torque-scale", type=float, default=1.0,
                        help="the plan's efforts times this (the self-test: 0, 0.5)")
    args = parser.parse_args()
    for path in args.plans:
        r = walk_lqr(path, args.steps, args)
        print(f"{path.name}: {r['half_cycles_walked']} of {args.steps}, feedback "
              f"{100 * r['feedback_share']:.0f} %, design {r['design_s']:.1f} s, walk "
              f"{r['walk_s']:.1f} s; {r['stopped']}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
