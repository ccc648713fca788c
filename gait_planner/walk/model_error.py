"""A simulated walker that differs from the plan's model, as a real robot differs from its
URDF (`walk(..., model_error=ModelError(...))`, `benchmarks/model_error.py`).

* mass_spread: every body's mass and inertia times its own factor drawn uniformly from
  [1 - spread, 1 + spread] (numpy's default generator, seeded by `seed`);
* friction: the Coulomb coefficient of every foot-ground contact (the plan's when None);
* contact_time_constant: s, MuJoCo's solref[0] of every contact (config/walk.yaml's when
  None): 2 ms is stiffer, 10 ms softer than the default 5 ms;
* torque_delay: s, the joints receive the controller's commands this late: the feed-forward
  torque, the torso feedback and the joint targets (angles and rates) computed at t - delay,
  while each joint's own PD on its angle and rate (kp, kd) acts on the present state, as a
  robot's joint-level impedance loop does under a late high-level command
  (`DelayedTorque`). Before the first command has arrived the joints hold the first one.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ModelError:
    """The differences of the module docstring; the default is none."""

    seed: int = 0
    mass_spread: float = 0.0
    friction: float | None = None
    contact_time_constant: float | None = None
    torque_delay: float = 0.0

    def __post_init__(self):
        if not 0.0 <= self.mass_spread < 1.0:
            raise ValueError(f"mass_spread must be in [0, 1), got {self.mass_spread}")
        if self.friction is not None and not self.friction > 0.0:
            raise ValueError(f"friction must be > 0, got {self.friction}")
        if self.contact_time_constant is not None and not self.contact_time_constant > 0.0:
            raise ValueError(f"contact_time_constant must be > 0 s, got "
                             f"{self.contact_time_constant}")
        if not self.torque_delay >= 0.0:
            raise ValueError(f"torque_delay must be >= 0 s, got {self.torque_delay}")

    def describe(self) -> str:
        """The differences in words ("none" if there are none)."""
        parts = ([f"masses and inertias x U[{1 - self.mass_spread:g}, "
                  f"{1 + self.mass_spread:g}] (seed {self.seed})"] if self.mass_spread else [])
        parts += [f"friction {self.friction:g}"] if self.friction is not None else []
        parts += ([f"contact time constant {1e3 * self.contact_time_constant:g} ms"]
                  if self.contact_time_constant is not None else [])
        parts += [f"torque delay {1e3 * self.torque_delay:g} ms"] if self.torque_delay else []
        return ", ".join(parts) or "none"

    def apply(self, model) -> dict[str, float]:
        """Change the compiled MuJoCo model in place (masses and inertias, with the
        constants derived from them, `mj_setConst`; friction; contact time constant);
        returns the mass factor drawn for each body, by name."""
        import mujoco

        factors = {}
        if self.mass_spread:
            rng = np.random.default_rng(self.seed)
            for b in range(1, model.nbody):  # body 0 is the world
                f = float(rng.uniform(1.0 - self.mass_spread, 1.0 + self.mass_spread))
                model.body_mass[b] *= f
                model.body_inertia[b] *= f
                factors[model.body(b).name] = f
            mujoco.mj_setConst(model, mujoco.MjData(model))  # subtree masses, inverse weights
        if self.friction is not None:
            model.geom_friction[:, 0] = self.friction
        if self.contact_time_constant is not None:
            model.geom_solref[:, 0] = self.contact_time_constant
        return factors


class DelayedTorque:
    """The torque a joint applies when its command arrives `steps` simulation steps late:
    `__call__(command, kp_q)` takes the command of this step (the torque the controller
    would apply now plus kp q, i.e. with the joint's own position term taken out) and
    returns the command of `steps` steps ago (the first one until then) minus kp q now."""

    def __init__(self, steps: int):
        self.queue: deque[np.ndarray] = deque(maxlen=steps + 1)

    def __call__(self, command: np.ndarray, kp_q: np.ndarray) -> np.ndarray:
        if not self.queue:
            self.queue.extend([command.copy()] * self.queue.maxlen)
        self.queue.append(command.copy())
        return self.queue[0] - kp_q
