"""The independent verifier's limits on a discrete plan (`gait_planner.verify.checks`; the
continuous certificate's are `gait_planner.verify.continuous.LIMITS`)."""

LIMITS = {
    "constraint": 1e-9,  # m (and dimensionless for director conditions), every node
    "contact": 1e-9,  # m, held points: drift over an interval and height
    "ground": 1e-9,  # m, lowest contact point
    "dynamics": 1e-8,  # relative full discrete Euler-Lagrange residual
    "actuation": 1e-9,  # relative: phi entries, couple form, net moment, axis, efforts
    "force": 1e-9,  # relative to max(1 N, |F|): unilateral and friction cone
    "periodicity": 1e-8,  # m
    "periodic_force": 1e-9,  # relative
    "cost": 1e-9,  # relative
    "time": 1e-9,  # relative (interval lengths, duration)
    "scaling": 1e-9,  # relative excess of sigma over its bounds (IPOPT relaxes bounds)
    "energy": 1e-9,  # relative, potential energy
}
