"""The optimal-control tests' fixtures: `solved` (test/solved_plans.py), shared with the
verifier's tests."""

from solved_plans import solved  # noqa: F401  (a fixture)
