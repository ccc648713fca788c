"""gait_planner: DMOCC gait optimisation of multibody walkers (ROS 2 package).

The Python API (`gait_planner.api`; loaded on first use, so importing a submodule stays
light): ``from gait_planner import PlanRequest, plan, check, record, summary``, and for a
plan that begins at a given state ``standing_start`` or ``start_of_recording`` (or
``start_of_plan``, ``start_of_velocity``, ``start_of_joint_state``) passed to
``plan(..., start=)``; ``walk_replanned`` walks a request from standing in MuJoCo,
re-planned at every strike.

One BLAS thread for CasADi's bundled OpenBLAS (read when CasADi first loads its IPOPT
plugin, so this has to run before the first solver is built): MUMPS then factorises the
same way every time and IPOPT takes the same path on every run. With two threads walker3d's cold solve took 160 or 199 iterations
depending on the run's threading, and spent a third of its time spinning in the kernel
(benchmarks/HISTORY.md).

numpy's OpenBLAS chooses its kernels by CPU (DYNAMIC_ARCH; CasADi's is built for one core
type): the kinematic guess's Gauss-Newton solves then differ in the last bits from machine
to machine, and the cold start ends in another local minimum. Measured on walker3d's
default request (compiled derivatives), numpy's kernels forced to Haswell or Zen: 96
iterations, J = 20.7801 J s; SkylakeX (what an AVX-512 Intel machine picks): 118, J =
20.8470; Prescott: 79, J = 20.8936. The kernels are therefore pinned to Haswell (any x86-64
CPU with AVX2), which takes effect only if this package is imported before numpy loads
OpenBLAS. Values set by the caller are kept (a CPU without AVX2 needs
OPENBLAS_CORETYPE=Prescott).
"""

import os
import platform

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_name, "1")
if platform.machine() in ("x86_64", "AMD64"):
    os.environ.setdefault("OPENBLAS_CORETYPE", "Haswell")

_API = ("PlanRequest", "PlanResult", "Planner", "RequestError", "StartError", "StartState",
        "check", "plan", "record", "standing_start", "start_of_joint_state", "start_of_plan",
        "start_of_recording", "start_of_velocity", "summary", "walk_replanned")
__all__ = list(_API)

from gait_planner.lazy import lazy_exports  # noqa: E402  (after the environment above)

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(_API, "api"))
