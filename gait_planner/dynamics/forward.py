"""Forward simulation with the variational integrator and the discrete null space method.

At each node n the unknowns are the nodal increments u_{n+1} (ndof,) of
q_{n+1} = F_d(u_{n+1}, q_n) and, if contact points are held, their multipliers lambda_n
(ground force on the body, N). Newton's method solves (paper eqs. 1-2, reduced by P^T)

    P^T(q_n) [p_n + D1 L_d(q_n, q_{n+1}, h_n) + h_n/2 B^T(q_n) tau_n + w_n G_C^T lambda_n] = 0
    G_C (q_{n+1} - q_n) = 0            (held contact points do not move)

with the incoming discrete momentum p_n = D2 L_d(q_{n-1}, q_n, h_{n-1}) + f+_{n-1}
(p_0 = M P(q_0) nu_0, the continuous Legendre transform of the initial velocity) and
w_n = (h_{n-1} + h_n)/2 (h_0/2 at n = 0). With this sign lambda_n is the force the ground
exerts on the body (the usual multiplier of eq. 1 is its negative). Internal and joint constraints hold exactly by
construction of F_d; the contact constraints are linear in q and hold to Newton tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import casadi as ca
import numpy as np

from gait_planner.buffered import bind
from gait_planner.dynamics.discrete import DiscreteMechanics


class SimulationError(RuntimeError):
    """Newton's method did not converge at a step."""


@dataclass(frozen=True)
class Trajectory:
    """Nodes n = 0..N of a simulation. Shapes: times (N+1,), q (N+1, k), p (N+1, k)
    momenta p-_n (p_0 the initial one), u (N, ndof), tau (N, nt), multipliers (N, nc),
    newton_iterations (N,)."""

    times: np.ndarray
    q: np.ndarray
    p: np.ndarray
    u: np.ndarray
    tau: np.ndarray
    multipliers: np.ndarray
    newton_iterations: np.ndarray


class Simulator:
    """Steps one multibody system with a fixed set of held contact points."""

    def __init__(self, mech: DiscreteMechanics, contacts: Sequence[str] = (),
                 tolerance: float = 1e-13, max_iterations: int = 30):
        mb = self.mb = mech.mb
        self.mech = mech
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        C = (np.vstack([mb.contact_rows(c) for c in contacts]) if contacts
             else np.zeros((0, mb.k)))
        nc = self.nc = C.shape[0]
        self.contacts, self._contact_rows = tuple(contacts), C
        u, lam = ca.SX.sym("u", mb.ndof), ca.SX.sym("lambda", nc)
        q, p = ca.SX.sym("q", mb.k), ca.SX.sym("p", mb.k)
        h, w, tau = ca.SX.sym("h"), ca.SX.sym("w"), ca.SX.sym("tau", mb.nt)
        q_next = mb.reparametrise(u, q)
        force = (p + mech.discrete_lagrangian_d1(q, q_next, h)
                 + 0.5 * h * ca.mtimes(mb.actuation(q), tau) + w * ca.mtimes(ca.DM(C).T, lam))
        res = ca.vertcat(ca.mtimes(mb.null_space(q).T, force), ca.mtimes(ca.DM(C), q_next - q))
        x = ca.vertcat(u, lam)
        self._newton = ca.Function(
            "newton_step", [x, q, p, h, w, tau], [res, ca.densify(ca.jacobian(res, x))],
            ["x", "q", "p", "h", "w", "tau"], ["r", "J"],
        ).expand()
        p_next = (mech.discrete_lagrangian_d2(q, q_next, h)
                  + 0.5 * h * ca.mtimes(mb.actuation(q_next), tau))
        self._advance = ca.Function(
            "advance", [u, q, h, tau], [q_next, p_next], ["u", "q", "h", "tau"],
            ["q_next", "p_next"],
        ).expand()
        self._mass_max = float(np.abs(mb.mass_diagonal).max())
        # Numeric evaluation through CasADi's buffer interface: the arguments and results
        # are numpy arrays bound once, so a Newton iteration converts nothing (measured in
        # benchmarks/HISTORY.md). Not thread-safe: one Simulator per thread.
        n = mb.ndof + nc
        self._in = {"x": np.zeros(n), "q": np.zeros(mb.k), "p": np.zeros(mb.k),
                    "h": np.zeros(1), "w": np.zeros(1), "tau": np.zeros(mb.nt)}
        self._res, self._jac_flat = np.zeros(n), np.zeros(n * n)
        self._jac = self._jac_flat.reshape(n, n, order="F")  # a view: CasADi is column-major
        self._newton_eval = bind(
            self._newton, [self._in[k] for k in ("x", "q", "p", "h", "w", "tau")],
            [self._res, self._jac_flat])
        self._q_next, self._p_next = np.zeros(mb.k), np.zeros(mb.k)
        self._advance_eval = bind(
            self._advance, [self._in["x"][: mb.ndof], self._in["q"], self._in["h"],
                            self._in["tau"]], [self._q_next, self._p_next])

    def initial_momentum(self, q0: np.ndarray, nu0: np.ndarray) -> np.ndarray:
        """p_0 = M P(q_0) nu_0 (k,)."""
        return self.mb.mass_diagonal * (np.array(self.mb.null_space(q0)) @ nu0)

    def step(self, q: np.ndarray, p: np.ndarray, h: float, w: float, tau: np.ndarray,
             guess: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
        """One step: returns (x = (u, lambda), q_next, Newton iterations)."""
        x, res, jac = self._in["x"], self._res, self._jac
        x[:] = guess
        self._in["q"][:], self._in["p"][:], self._in["tau"][:] = q, p, tau
        self._in["h"][0], self._in["w"][0] = h, w
        # Converged when the residual is below tolerance relative to the momentum, or at
        # its round-off floor (M (q_next - q)/h loses eps |q| |M| / h), or when Newton's
        # update no longer changes x.
        floor = 4 * np.finfo(float).eps * self._mass_max * max(1.0, np.abs(q).max()) / h
        tol = max(self.tolerance * max(1.0, float(np.abs(p).max())), floor)
        for it in range(1, self.max_iterations + 1):
            self._newton_eval()
            if not np.all(np.isfinite(res)):
                raise SimulationError("the residual is not finite")
            if np.abs(res).max() <= tol:
                break
            try:
                dx = np.linalg.solve(jac, res)
            except np.linalg.LinAlgError:
                raise SimulationError("the Newton matrix is singular") from None
            x -= dx
            if np.abs(dx).max() <= 4 * np.finfo(float).eps * max(1.0, np.abs(x).max()):
                break
        else:
            raise SimulationError(
                f"Newton's method did not converge in {self.max_iterations} iterations "
                f"(residual {np.abs(res).max():.3e}, step h = {h})"
            )
        self._advance_eval()
        return x.copy(), self._q_next.copy(), it - 1

    def largest_rotation(self, q0: np.ndarray, q1: np.ndarray) -> tuple[str, float]:
        """The body whose triad turns most from q0 to q1, and the angle (deg)."""
        angles = []
        for i in range(self.mb.nb):
            D0 = q0[12 * i + 3 : 12 * i + 12].reshape(3, 3)  # rows d1, d2, d3
            D1 = q1[12 * i + 3 : 12 * i + 12].reshape(3, 3)
            cos = np.clip(0.5 * (np.trace(D0 @ D1.T) - 1.0), -1.0, 1.0)
            angles.append(float(np.degrees(np.arccos(cos))))
        i = int(np.argmax(angles))
        return self.mb.body_names[i], angles[i]

    def run(self, q0: np.ndarray, nu0: np.ndarray, time_steps: Sequence[float],
            torques: Callable[[float], np.ndarray] | None = None) -> Trajectory:
        """Simulate from q_0 with initial generalised velocity nu_0 over the given steps.

        torques(t) gives the joint torques (nt,) held constant on [t_n, t_{n+1}] (evaluated
        at the interval midpoint); None means passive motion.
        """
        mb = self.mb
        if self.nc:
            rank = np.linalg.matrix_rank(self._contact_rows @ np.array(mb.null_space(q0)))
            if rank < self.nc:
                raise SimulationError(
                    f"the held contact points ({', '.join(self.contacts)}) give {self.nc} "
                    f"constraints of which only {rank} are independent (e.g. two points of "
                    "one foot); hold fewer points")
        hs = np.asarray(time_steps, dtype=float)
        n = hs.size
        times = np.concatenate([[0.0], np.cumsum(hs)])
        q = np.zeros((n + 1, mb.k))
        p = np.zeros((n + 1, mb.k))
        us = np.zeros((n, mb.ndof))
        taus = np.zeros((n, mb.nt))
        lams = np.zeros((n, self.nc))
        iters = np.zeros(n, dtype=int)
        q[0], p[0] = q0, self.initial_momentum(q0, nu0)
        x = np.zeros(mb.ndof + self.nc)
        for i in range(n):
            h = hs[i]
            w = 0.5 * (h + (hs[i - 1] if i > 0 else 0.0))
            tau = np.zeros(mb.nt) if torques is None else np.asarray(torques(times[i] + h / 2))
            try:
                x, q[i + 1], iters[i] = self.step(q[i], p[i], h, w, tau, x)
            except SimulationError as err:
                hint = self._diagnosis(q[i - 1], q[i]) if i > 0 else ""
                raise SimulationError(f"step {i} (t = {times[i]:.6g} s): {err}{hint}") from None
            us[i], lams[i], taus[i] = x[: mb.ndof], x[mb.ndof :], tau
            p[i + 1] = self._p_next  # D2 L_d(q_i, q_i+1) + f+_i, evaluated by `step`
        return Trajectory(times, q, p, us, taus, lams, iters)

    def _diagnosis(self, q_prev: np.ndarray, q: np.ndarray) -> str:
        """Why a step may have no solution: the fastest body of the previous step.

        The trapezoidal discrete Lagrangian's momentum of a body turning by theta per step
        grows like sin(theta)/h and peaks at theta = 90 deg: a body whose (incoming)
        momentum exceeds that peak has no next configuration. The equations fold there
        (Newton stalls at a singular Jacobian; a homotopy from the previous increment turns
        back before reaching the step): the step is too large for the motion, and only a
        smaller h helps (benchmarks/HISTORY.md, "dt = 0.05").
        """
        body, angle = self.largest_rotation(q_prev, q)
        text = f"; in the previous step {body} turned by {angle:.0f} deg"
        if angle > 30.0:
            text += (" (the discrete equations have no solution once a body would turn by "
                     "about 90 deg in one step): reduce the time step")
        else:
            text += (" (fast or stiff motion, e.g. a light body between a pinned point and "
                     "a heavy load, needs a smaller time step)")
        return text
