"""What every benchmark script does before anything else: one thread per process for BLAS and
OpenMP, set before numpy loads (numpy reads it once, on import), so that timings are of one core
and the workers of a parallel run share the machine's cores instead of fighting over them; and
this folder and the checkout on ``sys.path``, so that the scripts import one another by name and
``import mzc`` is this checkout's, however a script is started (``python benchmarks/x.py``, or a
test importing it).

A script imports it first: ``import startup``, or ``from startup import HERE`` when it needs
this folder. Where the shared data lies is ``corpora``'s.
"""

import os
import sys
from pathlib import Path

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

HERE = Path(__file__).resolve().parent
for _folder in (HERE, HERE.parent):   # the checkout first, as sys.path.insert(0, ...) of each in turn
    if str(_folder) not in sys.path:
        sys.path.insert(0, str(_folder))
