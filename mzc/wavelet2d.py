"""Numerics of the dwt2d codec: hole filling, the 2D wavelet pyramid, quantisation, rate control.

The encoder fills invalid nodes smoothly (so the transform spends no bits on a jump at
the mask edge), takes a multi-level 2D DWT (PyWavelets, periodization mode: exactly as
many coefficients as nodes), and quantises each subband with its own step. Coefficients
whose synthesis support misses every valid node cannot change the decoded surface and
are not coded at all. ``reconstruct`` is the decoder's own inverse, so the encoder sees
exactly what the decoder will produce and can add the correction layer that makes a
max-error bound hold.
"""

import warnings

import numpy as np
import pywt
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from mzc.errors import MzcError

WAVELETS = ("bior4.4", "bior2.2", "bior3.3", "db2", "db4", "sym4", "coif1", "haar")
MODE = "periodization"
MAX_LEVELS = 12
MAX_QUANTUM = 1 << 45       # largest |quantised value|; keeps every class below entropy.MAX_CLASSES


# --------------------------------------------------------------------------- fill


def laplace_fill(z, valid):
    """``z`` with invalid nodes replaced by the discrete harmonic interpolant of the valid ones.

    Solves the 5-point Laplace equation on the invalid nodes with the valid nodes as
    Dirichlet data and a free (Neumann) grid border: one sparse solve, smooth across the
    mask edge, and it costs no bits because the decoder never needs it.
    """
    filled = np.where(valid, z, 0.0)
    if valid.all() or not valid.any():
        return filled
    rows, cols = z.shape
    unknown = np.flatnonzero(~valid.ravel())
    index = np.full(rows * cols, -1)
    index[unknown] = np.arange(len(unknown))
    r, c = np.divmod(unknown, cols)
    diagonal = np.zeros(len(unknown))
    rhs = np.zeros(len(unknown))
    row_ids, col_ids = [], []
    for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        inside = (r + dr >= 0) & (r + dr < rows) & (c + dc >= 0) & (c + dc < cols)
        neighbour = (r + dr) * cols + (c + dc)
        diagonal += inside
        known = inside & valid.ravel()[np.where(inside, neighbour, 0)]
        rhs[known] += filled.ravel()[neighbour[known]]
        free = inside & ~known
        row_ids.append(np.flatnonzero(free))
        col_ids.append(index[neighbour[free]])
    row_ids, col_ids = np.concatenate(row_ids), np.concatenate(col_ids)
    matrix = sp.csr_matrix((np.full(len(row_ids), -1.0), (row_ids, col_ids)), shape=(len(unknown),) * 2)
    matrix = matrix + sp.diags(diagonal)
    filled.ravel()[unknown] = spsolve(matrix.tocsc(), rhs)
    return filled


# --------------------------------------------------------------------------- transform


def default_levels(shape, wavelet):
    """Levels until the coarsest band is about 16 nodes across (measured: deeper stops paying)."""
    return int(max(0, min(MAX_LEVELS, np.floor(np.log2(max(1, min(shape) / 16))))))


def band_shapes(shape, wavelet, levels):
    """Shapes of the bands in coding order: the approximation, then per level (coarse to fine) one shape."""
    if levels == 0:
        return [tuple(shape)]
    shapes = pywt.wavedecn_shapes(tuple(shape), wavelet, mode=MODE, level=levels)
    return [tuple(shapes[0])] + [tuple(s["ad"]) for s in shapes[1:]]


def forward(z, wavelet, levels):
    """[approximation, (H, V, D) coarse to fine, ...] of the filled heights."""
    if levels == 0:
        return [z.copy()]
    with warnings.catch_warnings():  # pywt warns when a level is deeper than the filter allows
        warnings.simplefilter("ignore")
        return pywt.wavedec2(z, wavelet, mode=MODE, level=levels)


def inverse(bands, shape, wavelet, levels):
    """Heights from dequantised bands, cropped to ``shape``: the decoder's reconstruction."""
    if levels == 0:
        return bands[0].copy()
    return pywt.waverec2(bands, wavelet, mode=MODE)[: shape[0], : shape[1]]


def relevance(valid, wavelet, levels):
    """Per band, True where the coefficient's synthesis support touches a valid node.

    Computed as the transform of the mask with every filter replaced by a box of the
    filter length (non-negative, so the test '> 0' is exact): a superset of the true
    support, identical in encoder and decoder because both see the same mask.
    """
    if levels == 0:
        return [valid.copy()]
    length = pywt.Wavelet(wavelet).dec_len
    box = [np.ones(length)] * 4
    boxes = forward(valid.astype(np.float64), pywt.Wavelet("box", filter_bank=box), levels)
    return [boxes[0] > 0] + [tuple(b > 0 for b in level) for level in boxes[1:]]


# --------------------------------------------------------------------------- quantisation


def level_steps(base, levels, level_gain=1.0, approximation_gain=1.0):
    """Steps for [approximation, (H, V, D) coarse to fine]: ``base`` times level_gain**(level - 1).

    Level 1 is the finest; level_gain > 1 quantises coarse levels more coarsely.
    """
    steps = [base * approximation_gain * level_gain ** max(levels - 1, 0)]
    for level in range(levels, 0, -1):
        steps += [base * level_gain ** (level - 1)] * 3
    return steps


def quantise(bands, steps, deadzone=0.5):
    """Integer bands: round(|c|/step + 0.5 - deadzone) with c's sign (deadzone 0.5 = rounding)."""
    flat = flatten(bands)
    out = []
    for band, step in zip(flat, steps):
        scaled = np.abs(band) / step
        if scaled.size and scaled.max() >= MAX_QUANTUM:
            raise MzcError(f"quantisation step {step:g} is too small for these heights")
        out.append((np.sign(band) * np.floor(scaled + 1.0 - deadzone)).astype(np.int64))
    return unflatten(out, len(bands) - 1)


def dequantise(qbands, steps):
    """Bands of step * q, in the layout ``inverse`` takes."""
    return unflatten([q * s for q, s in zip(flatten(qbands), steps)], len(qbands) - 1)


def flatten(bands):
    """[approximation, H, V, D, H, V, D, ...] from the pywt layout."""
    return [bands[0]] + [b for level in bands[1:] for b in level]


def unflatten(flat, levels):
    """The pywt layout from a flat band list."""
    return [flat[0]] + [tuple(flat[1 + 3 * i: 4 + 3 * i]) for i in range(levels)]


def mask_bands(qbands, relevant):
    """Zero the coefficients that cannot reach a valid node."""
    return unflatten([np.where(r, q, 0) for q, r in zip(flatten(qbands), flatten(relevant))],
                     len(qbands) - 1)


# --------------------------------------------------------------------------- correction


def correction_step(max_error):
    """Residual step 2E shrunk by one part in 1e9, so rounding error plus float noise stays <= E."""
    return 2.0 * max_error * (1.0 - 1e-9)


def corrections(z, decoded, valid, step):
    """Integer residuals k at the valid nodes (raster order) so |z - (decoded + k*step)| <= step/2."""
    return np.round((z[valid] - decoded[valid]) / step).astype(np.int64)


# --------------------------------------------------------------------------- rate control


def search_step(cost, target, low, high, iterations=14):
    """Largest x in [low, high] (log bisection) whose ``cost(x)`` stays <= target.

    ``cost`` must grow with x; returns the best feasible x, or ``low`` when none is.
    """
    best = low
    for _ in range(iterations):
        middle = np.sqrt(low * high)
        if cost(middle) <= target:
            best = low = middle
        else:
            high = middle
        if high / low < 1.01:
            break
    return best
