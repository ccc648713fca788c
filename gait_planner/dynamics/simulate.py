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
        u, lam = ca.SX.sym("u", mb.ndof), ca.SX.sym("lambda", nc)
        q, p = ca.SX.sym("q", mb.k), ca.SX.sym("p", mb.k)
        h, w, tau = ca.SX.sym("h"), ca.SX.sym("w"), ca.SX.sym("tau", mb.nt)
        q_next = mb.reparametrise(u, q)
        force = (p + mech.discrete_lagrangian_d1(q, q_next, h)
                 + 0.5 * h * ca.mtimes(mb.actuation(q), tau) + w * ca.mtimes(ca.DM(C).T, lam))
        res = ca.vertcat(ca.mtimes(mb.null_space(q).T, force), ca.mtimes(ca.DM(C), q_next - q))
        x = ca.vertcat(u, lam)
        self._newton = ca.Function(
            "newton_step", [x, q, p, h, w, tau], [res, ca.jacobian(res, x)]
        ).expand()
        self._mass_max = float(np.abs(mb.mass_diagonal).max())

    def initial_momentum(self, q0: np.ndarray, nu0: np.ndarray) -> np.ndarray:
        """p_0 = M P(q_0) nu_0 (k,)."""
        return self.mb.mass_diagonal * (np.array(self.mb.null_space(q0)) @ nu0)

    def step(self, q: np.ndarray, p: np.ndarray, h: float, w: float, tau: np.ndarray,
             guess: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
        """One step: returns (x = (u, lambda), q_next, Newton iterations)."""
        x = guess.copy()
        # Converged when the residual is below tolerance relative to the momentum, or at
        # its round-off floor (M (q_next - q)/h loses eps |q| |M| / h), or when Newton's
        # update no longer changes x.
        floor = 4 * np.finfo(float).eps * self._mass_max * max(1.0, np.abs(q).max()) / h
        tol = max(self.tolerance * max(1.0, float(np.abs(p).max())), floor)
        for it in range(1, self.max_iterations + 1):
            res, jac = self._newton(x, q, p, h, w, tau)
            res = np.array(res).ravel()
            if not np.all(np.isfinite(res)):
                raise SimulationError("the residual is not finite")
            if np.abs(res).max() <= tol:
                break
            dx = np.linalg.solve(np.array(jac), res)
            x = x - dx
            if np.abs(dx).max() <= 4 * np.finfo(float).eps * max(1.0, np.abs(x).max()):
                break
        else:
            raise SimulationError(
                f"Newton's method did not converge in {self.max_iterations} iterations "
                f"(residual {np.abs(res).max():.3e}, step h = {h})"
            )
        q_next = np.array(self.mb.reparametrise(x[: self.mb.ndof], q)).ravel()
        return x, q_next, it - 1

    def run(self, q0: np.ndarray, nu0: np.ndarray, time_steps: Sequence[float],
            torques: Callable[[float], np.ndarray] | None = None) -> Trajectory:
        """Simulate from q_0 with initial generalised velocity nu_0 over the given steps.

        torques(t) gives the joint torques (nt,) held constant on [t_n, t_{n+1}] (evaluated
        at the interval midpoint); None means passive motion.
        """
        mb, mech = self.mb, self.mech
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
                raise SimulationError(f"step {i} (t = {times[i]:.6g} s): {err}") from None
            us[i], lams[i], taus[i] = x[: mb.ndof], x[mb.ndof :], tau
            p[i + 1] = mech.momentum(q[i], q[i + 1], h, tau)
        return Trajectory(times, q, p, us, taus, lams, iters)
