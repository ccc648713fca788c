"""Numeric evaluation of a CasADi Function through its buffer interface.

``Function.__call__`` converts every argument to a DM and every result back (about 20-60 us
a call from Python); a bound buffer reads and writes numpy arrays in place, so a loop that
evaluates a small Function many times (a Newton or Levenberg-Marquardt iteration) converts
nothing. The values are CasADi's own evaluation, bit for bit.
"""

from __future__ import annotations

from typing import Callable

import casadi as ca
import numpy as np


def bind(function: ca.Function, args: list[np.ndarray], results: list[np.ndarray]
         ) -> Callable[[], object]:
    """A no-argument callable evaluating `function` from the arrays `args` into the arrays
    `results` (one per input and output, float64, contiguous, each with the input's or
    output's number of nonzeros; a matrix result is column-major). Not thread-safe: one
    binding per thread."""
    buffer, evaluate = function.buffer()
    for i, a in enumerate(args):
        buffer.set_arg(i, memoryview(a))
    for i, r in enumerate(results):
        buffer.set_res(i, memoryview(r))
    return lambda: (buffer, evaluate())  # keeps the buffer alive with the callable
