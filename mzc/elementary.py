"""sin, cos, atan2, exp, log and log2 with the same bits on every machine.

numpy picks SIMD loops for exp, log, arctan2 and power when it starts, by what the CPU
offers: its AVX-512 loops give other last bits than its AVX2 ones, so a slice, a view
choice or an encoder's step search computed with them would give other bytes on another
machine. The C library's functions differ between its builds too. These are mzc's own
(``_elementary.c``: IEEE additions, multiplications and divisions in a fixed order),
within 1-2 ulp of the true values, and they are what every output of mzc is computed
with (spec/zgrid.md, "Same bytes on every machine").

Each takes numbers or arrays (broadcast together for atan2) and returns a float for
numbers, a float64 array otherwise.
"""

import numpy as np

from mzc import _elementary


def _applied(kernel, *arrays):
    """``kernel`` (a function of _elementary) over ``arrays`` broadcast together, in their shape."""
    arrays = [np.asarray(a, dtype=np.float64) for a in arrays]
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    inputs = [np.ascontiguousarray(np.broadcast_to(a, shape)).reshape(-1) for a in arrays]
    out = np.empty(shape)
    kernel(*inputs, out.reshape(-1))
    return float(out) if not shape else out


def sin(x):
    """The sine of ``x`` (radians)."""
    return _applied(_elementary.sin, x)


def cos(x):
    """The cosine of ``x`` (radians)."""
    return _applied(_elementary.cos, x)


def atan2(y, x):
    """The angle of the point (x, y) from the +x axis, in [-pi, pi] (C's atan2)."""
    return _applied(_elementary.atan2, y, x)


def exp(x):
    """e to the power ``x``."""
    return _applied(_elementary.exp, x)


def log(x):
    """The natural logarithm of ``x`` (NaN below 0, -inf at 0)."""
    return _applied(_elementary.log, x)


def log2(x):
    """The base-2 logarithm of ``x``, exact at powers of 2."""
    return _applied(_elementary.log2, x)
