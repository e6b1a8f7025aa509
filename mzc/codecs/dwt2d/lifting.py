"""The 2D wavelet transform of dwt2d 3.0: CDF 9/7 or LeGall 5/3 by lifting (spec/dwt2d.md).

Non-expansive (a grid of R x C nodes gives R x C coefficients) without wrapping round:
each level extends the signal by whole-sample symmetry at its ends, as JPEG 2000 does,
so a grid's first and last rows are never joined into a false edge (the periodisation of
dwt2d 2.0 joined them: 15-20% of a face's file on a spherical grid). Along the rows of a
grid whose columns make a full turn the extension is periodic instead, so the seam is no
edge either. Pure functions over numpy arrays; one level transforms every row of the
grid, then every column.
"""

import numpy as np

# predict and update coefficients, then the scales of the low and high bands (DC gain sqrt 2)
CDF97 = ((-1.586134342059924, -0.052980118572961, 0.882911075530934, 0.443506852043971),
         1.230174104914001)
LEGALL53 = ((-0.5, 0.25), 1.0)
LIFTINGS = {"bior4.4": CDF97, "bior2.2": LEGALL53}
# synthesis reach of a low and a high coefficient (samples either side of its own)
REACH = {"bior4.4": (3, 4), "bior2.2": (1, 2)}
STRIP_VALUES = 1 << 20   # a pass lifts this many values at a time (columns of axis 0's strips): its temporaries
                         # are reused and stay in cache, where whole-grid ones made the kernel hand out fresh pages


def scales(wavelet):
    """(low, high) band scales: sqrt(2) / K and -K / sqrt(2), K the lifted value of a constant (the
    signs and gains of PyWavelets' bior4.4 and bior2.2)."""
    k = LIFTINGS[wavelet][1]
    return np.sqrt(2) / k, -k / np.sqrt(2)


def split_lengths(n):
    """(low, high) coefficient counts of a level along an axis of n samples."""
    return (n + 1) // 2, n // 2


def wraps(periodic, n):
    """Whether an axis of n samples is extended periodically at this level (an even length)."""
    return periodic and n % 2 == 0 and n > 2


def following(values, count, periodic):
    """values[k + 1] for k < count: past the end the symmetric extension gives values[-1]
    (x[n] mirrors x[n - 2]); a periodic one wraps to values[0]. Slices, not index arrays:
    the synthesis runs once per step the encoder's rate control tries."""
    if periodic:
        return np.roll(values, -1, axis=0)
    if count < len(values):
        return values[1:count + 1]
    return np.concatenate([values[1:count + 1], values[-1:].repeat(count + 1 - len(values), axis=0)])


def preceding(values, count, periodic):
    """values[k - 1] for k < count: before the start the symmetric extension gives values[0]
    (x[-1] mirrors x[1]); a periodic one wraps to values[-1]."""
    if periodic:
        return np.roll(values, 1, axis=0)
    return np.concatenate([values[:min(count, 1)], values[:max(count - 1, 0)]])


def extended(values, count):
    """values[k] for k < count, repeating the last one past the end (x[n] mirrors x[n - 2])."""
    if count <= len(values):
        return values[:count]
    return np.concatenate([values, values[-1:].repeat(count - len(values), axis=0)])


def lift(even, odd, steps, cyclic, sign):
    """Apply (sign +1) or undo (sign -1, in reverse order) the lifting steps to ``even`` and
    ``odd`` in place: even steps predict the odd samples from their two even neighbours, odd
    steps update the even samples from their two odd neighbours (odd += sign c (e[k] +
    e[k+1]), even += sign c (o[k-1] + o[k]))."""
    order = list(enumerate(steps)) if sign > 0 else list(enumerate(steps))[::-1]
    for index, c in order:
        if index % 2 == 0:
            change = even[:len(odd)] + following(even, len(odd), cyclic)
            change *= sign * c
            odd += change
        else:
            here = odd if cyclic else extended(odd, len(even))
            change = preceding(odd, len(even), cyclic) + here
            change *= sign * c
            even += change


def strips(shape):
    """Index tuples that cut an array of ``shape`` into strips of whole columns of axis 0,
    about STRIP_VALUES values each (the whole of a 1-D array)."""
    if len(shape) < 2:
        return [...]
    width = max(1, STRIP_VALUES // max(shape[0], 1))
    return [(slice(None), slice(first, first + width)) for first in range(0, max(shape[1], 1), width)]


def analyse(x, wavelet, periodic=False):
    """(low, high) of one level along axis 0 of ``x``: ceil(n/2) and floor(n/2) coefficients."""
    steps, _k = LIFTINGS[wavelet]
    low_scale, high_scale = scales(wavelet)
    x = np.asarray(x, dtype=np.float64)
    if len(x) == 1:   # a constant's low coefficient: the DC gain, sqrt 2
        return x * np.sqrt(2), x[:0]
    cyclic = wraps(periodic, len(x))
    low, high = (np.empty((length,) + x.shape[1:]) for length in split_lengths(len(x)))
    for part in strips(x.shape):
        even, odd = x[0::2][part].copy(), x[1::2][part].copy()
        lift(even, odd, steps, cyclic, +1)
        np.multiply(even, low_scale, out=low[part])
        np.multiply(odd, high_scale, out=high[part])
    return low, high


def synthesise(low, high, wavelet, periodic=False):
    """Inverse of ``analyse``: the signal along axis 0."""
    steps, _k = LIFTINGS[wavelet]
    low_scale, high_scale = scales(wavelet)
    n = len(low) + len(high)
    if n == 1:
        return low / np.sqrt(2)
    cyclic = wraps(periodic, n)
    x = np.empty((n,) + low.shape[1:])
    for part in strips(x.shape):
        even, odd = low[part] / low_scale, high[part] / high_scale
        lift(even, odd, steps, cyclic, -1)
        x[0::2][part], x[1::2][part] = even, odd
    return x


def forward(z, wavelet, levels, periodic=False):
    """Bands [LL, (H, V, D) coarse to fine ...]: H is high down the columns and low along the
    rows, V the reverse, D high both ways (PyWavelets' cH, cV, cD). ``periodic``: the rows wrap."""
    return pyramid(np.asarray(z, dtype=np.float64), lambda x, wrap: analyse(x, wavelet, wrap), levels, periodic)


def pyramid(values, split, levels, periodic):
    """The band layout of ``forward`` for a one-level ``split(x, periodic) -> (low, high)`` along
    axis 0: each level splits every row (wrapping when ``periodic``), then every column of both
    halves, and goes on with the part that is low both ways."""
    details = []
    low = values
    for _ in range(levels):
        row_low, row_high = (part.T for part in split(low.T, periodic))
        low, h = split(row_low, False)
        v, d = split(row_high, False)
        details.append((h, v, d))
    return [low] + details[::-1]


def inverse(bands, wavelet, periodic=False):
    """Heights from the bands of ``forward``."""
    low = bands[0]
    for h, v, d in bands[1:]:
        row_low, row_high = synthesise(low, h, wavelet), synthesise(v, d, wavelet)
        low = synthesise(row_low.T, row_high.T, wavelet, periodic).T
    return low


def reach_mask(mask, reach, periodic):
    """True where a True of ``mask`` lies within ``reach`` samples along axis 0 (wrapping when periodic)."""
    out = mask.copy()
    for shift in range(1, reach + 1):
        if periodic:
            out |= np.roll(mask, shift, axis=0) | np.roll(mask, -shift, axis=0)
        else:
            out[shift:] |= mask[:-shift]
            out[:-shift] |= mask[shift:]
    return out


def split_relevance(mask, wavelet, periodic=False):
    """(low, high) relevance of one level along axis 0: a coefficient whose synthesis reaches a
    True of ``mask`` (its low or high reach either side of its own sample)."""
    n = len(mask)
    if n == 1:
        return mask.copy(), mask[:0]
    mask = np.ascontiguousarray(mask)   # not a transposed or strided view: numpy's ORs of those ran 5x slower
    cyclic = wraps(periodic, n)
    low_reach, high_reach = REACH[wavelet]
    return reach_mask(mask, low_reach, cyclic)[0::2], reach_mask(mask, high_reach, cyclic)[1::2]


def relevance(valid, wavelet, levels, periodic=False):
    """Per band of ``forward``, True where the coefficient's synthesis touches a valid node."""
    return pyramid(np.asarray(valid, dtype=bool), lambda mask, wrap: split_relevance(mask, wavelet, wrap),
                   levels, periodic)
