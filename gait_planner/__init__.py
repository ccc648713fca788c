"""gait_planner: DMOCC gait optimisation of multibody walkers (ROS 2 package).

One BLAS thread for CasADi's bundled OpenBLAS (read when CasADi first loads its IPOPT
plugin, so this has to run before the first solver is built): MUMPS then factorises the
same way every time and IPOPT takes the same path on every run. With two threads walker3d's cold solve took 160 or 199 iterations
depending on the run's threading, and spent a third of its time spinning in the kernel
(benchmarks/REPORT.md). A value set by the caller is kept.
"""

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_name, "1")
