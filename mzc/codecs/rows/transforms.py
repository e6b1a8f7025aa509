"""The per-row transforms of the thesis (Ch. 5-7), forward and inverse, as plain numpy functions.

Every function works on the last axis, so it takes one row's valid span (1D, length m)
or a stack of spans of equal length (k x m) and transforms them in one call; the format
modules batch rows of equal span length this way. Quality truncation (which coefficients
a file keeps) lives with the file layouts in ``mzc.formats``; here a dropped coefficient
is simply a zero. See METHOD.md §3 and spec/{poly,dft,dct,dwt}.md.
"""

import numpy as np

from mzc.errors import MzcError

DEFAULT_WAVELET = "db1"
DEFAULT_LEVEL = 3
# pywt's 'symmetric' extension is MATLAB's default 'sym' mode, so lengths (and legacy
# thesis files) agree with wavedec in MATLAB.
WAVELET_MODE = "symmetric"
BASES = ("chebyshev", "power")


def kept(quality, count):
    """How many of ``count`` coefficients quality Q keeps: floor(Q*count/100), exact in integers."""
    return quality * count // 100


def fill_holes(span):
    """``span`` with NaN holes replaced by linear interpolation between their valid neighbours.

    A hole left as a jump (or zero) would cost many coefficients to describe and would
    smear into its neighbours on decoding; a straight line across it costs almost nothing.
    The ends of a span are valid by definition, so every hole has two neighbours.
    """
    filled = np.array(span, dtype=float)
    rows = filled.reshape(-1, filled.shape[-1])  # a view: writing rows writes ``filled``
    positions = np.arange(rows.shape[-1])
    for index in np.flatnonzero(np.isnan(rows).any(axis=-1)):
        bad = np.isnan(rows[index])
        rows[index, bad] = np.interp(positions[bad], positions[~bad], rows[index, ~bad])
    return filled


# --- polynomial (Ch. 5) -------------------------------------------------------------

FIT_BUDGET = 1 << 26      # basis values of one least-squares fit when encoding (512 MB)
RANK_TOLERANCE = np.finfo(float).eps   # times the samples: a fit's columns this dependent are dropped


def chebyshev_points(length):
    """The span's samples mapped to [-1, 1] (0 for a one-sample span)."""
    return np.linspace(-1.0, 1.0, length) if length > 1 else np.zeros(1)


def power_points(first, length, step):
    """The thesis's raw abscissae: 1-based column index times d2 (MATLAB ``y*depthScale2``)."""
    first = np.asarray(first, dtype=float)[..., None]
    return (first + np.arange(length)) * step


def poly_degree(degree, length):
    """The degree actually fitted: at most length-1, since m points fix at most m coefficients."""
    return min(degree, length - 1)


def poly_forward(spans, degree, basis="chebyshev", first=1, step=1.0):
    """Least-squares polynomial coefficients of each span (``least_squares``).

    ``chebyshev`` (default): coefficients of T0..Tn on the span mapped to [-1, 1], lowest
    first. The Chebyshev-Vandermonde matrix is well conditioned at any degree, so high
    degrees fit as well as the data allow and coefficients stay the size of the heights.
    ``power``: the thesis's ``polyfit`` on raw x = column*d2 (``first`` is the 1-based
    column of the span's first sample), highest power first as MATLAB stores them. The
    monomial Vandermonde matrix at x ~ 100 is hopelessly ill conditioned past degree ~20,
    and past ~40 the fit and its evaluation lose all digits: the thesis's "unstable" faces.
    """
    spans = np.asarray(spans, dtype=float)
    length = spans.shape[-1]
    n = poly_degree(degree, length)
    if length * (n + 1) > FIT_BUDGET:
        raise MzcError(f"a degree-{n} fit of rows of {length} samples needs {8 * length * (n + 1) / 1e9:.1f} GB "
                       f"(at most {8 * FIT_BUDGET / 1e9:.1f}): use a lower degree", field="degree")
    if basis == "chebyshev":
        vander = np.polynomial.chebyshev.chebvander(chebyshev_points(length), n)
        return least_squares(vander, spans.reshape(-1, length)).reshape(spans.shape[:-1] + (n + 1,))
    rows = np.atleast_2d(spans)
    xs = np.broadcast_to(np.atleast_2d(power_points(first, length, step)), rows.shape)
    fits = np.array([_power_fit(x, row, n) for x, row in zip(xs, rows)])
    return fits.reshape(spans.shape[:-1] + (n + 1,))


def _power_fit(x, row, n):
    """``polyfit`` of one row (its Vandermonde matrix, highest power first). A degree whose
    powers of x overflow cannot be fitted at all: that is an error, not a row of NaN."""
    with np.errstate(over="ignore", invalid="ignore"):
        scale = np.abs(x).max() ** (2 * n)
    if n and not (np.isfinite(scale) and scale > 0):
        raise MzcError(f"the power basis cannot fit degree {n} on columns up to x = {x.max():g} (x^{2 * n} "
                       "leaves binary64; the thesis's basis is unstable past degree ~40): use --basis chebyshev "
                       "or a lower degree", field="degree")
    fit = least_squares(np.vander(x, n + 1), row[None, :])[0]
    if not np.isfinite(fit).all():
        raise MzcError(f"the power basis fit of degree {n} failed (its Vandermonde matrix is singular in binary64): "
                       "use --basis chebyshev or a lower degree", field="degree")
    return fit


def least_squares(basis, values):
    """(k, p) coefficients c minimising |basis @ c_i - values_i| for each of the k rows of
    ``values`` (k, m), ``basis`` (m, p), by Householder QR of the basis with its columns
    scaled to unit length (as ``polyfit`` scales them).

    Written in numpy's elementwise operations and sums, not LAPACK's: LAPACK works through
    BLAS, whose kernels are chosen by the CPU and round differently, and a file must be the
    same bytes on every machine. Columns are taken in order until one lies within
    m * RANK_TOLERANCE (relative) of those before it: the fit then stops at the degree the
    basis can still tell apart in binary64, and the higher coefficients are 0 (LAPACK's
    lstsq would spread them at random over the dependent columns).
    """
    a = np.array(basis, dtype=float)
    b = np.array(values, dtype=float).T
    m, p = a.shape
    scale = np.sqrt((a * a).sum(axis=0))
    scale[scale == 0] = 1.0
    a /= scale
    rank = 0
    for j in range(min(m, p)):
        if not reflect(a, b, j, len(a) * RANK_TOLERANCE):
            break
        rank = j + 1
    coefficients = np.zeros((b.shape[1], p))
    for j in range(rank - 1, -1, -1):   # back substitution in R, the upper triangle of a
        known = (a[j, j + 1:rank, None] * coefficients[:, j + 1:rank].T).sum(axis=0)
        coefficients[:, j] = (b[j] - known) / a[j, j]
    return coefficients / scale


def reflect(a, b, j, tolerance):
    """One Householder step: ``a``'s column j zeroed below its diagonal, the same reflection
    applied to ``a``'s later columns and to every column of ``b`` (in place). False, and
    nothing changed, when column j is within ``tolerance`` of the columns before it."""
    v = a[j:, j].copy()
    norm = np.sqrt((v * v).sum())
    if not norm > tolerance:
        return False
    alpha = -norm if v[0] >= 0 else norm
    v[0] -= alpha
    factor = 2 / (v * v).sum()
    for target in (a[j:, j:], b[j:]):
        target -= (factor * v)[:, None] * (v[:, None] * target).sum(axis=0)
    return True


def poly_inverse(coefficients, length, basis="chebyshev", first=1, step=1.0):
    """Evaluate the polynomials of ``poly_forward`` at the span's samples: by Clenshaw's
    recurrence for Chebyshev, Horner's for powers, elementwise over the spans, so every
    machine decodes the same bits and memory is the output's whatever degree a file declares."""
    coefficients = np.asarray(coefficients, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        if basis == "chebyshev":
            return clenshaw(coefficients, chebyshev_points(length))
        x = power_points(first, length, step)
        values = np.zeros(coefficients.shape[:-1] + (length,))
        for index in range(coefficients.shape[-1]):   # Horner, highest power first as the coefficients are stored
            values = values * x + coefficients[..., index:index + 1]
        return values


def clenshaw(coefficients, points):
    """sum_i c_i T_i(t) at ``points`` t for each row of ``coefficients`` (..., p), lowest order first."""
    after = np.zeros(coefficients.shape[:-1] + points.shape)
    current = np.zeros_like(after)
    for index in range(coefficients.shape[-1] - 1, 0, -1):
        current, after = coefficients[..., index:index + 1] + 2 * points * current - after, current
    return coefficients[..., :1] + points * current - after


# --- DFT (Ch. 6, §6.2.2) --------------------------------------------------------------

def dft_length(length):
    """L = length(an) = floor((m+1)/2) - 1 for a span of m samples."""
    return (length + 1) // 2 - 1


def dft_forward(spans):
    """(a0, aN, an, bn) of METHOD.md §3: the thesis's sine-cosine series from ``fft``.

    d = fft(s), M = floor((m+1)/2); a0 = d(1)/m, an = 2 Re d(2..M)/m, bn = -2 Im d(2..M)/m
    and aN = d(M+1)/m. For even m, d(M+1) is the real Nyquist term; for odd m it is the
    conjugate of d(M) and carries nothing new, so aN is 0 there.
    """
    spans = np.asarray(spans, dtype=float)
    m = spans.shape[-1]
    d = np.fft.rfft(spans, axis=-1)
    big_m = (m + 1) // 2
    a0 = d[..., 0].real / m
    an = 2 * d[..., 1:big_m].real / m
    bn = -2 * d[..., 1:big_m].imag / m
    a_last = d[..., big_m].real / m if m % 2 == 0 else np.zeros_like(a0)
    return a0, a_last, an, bn


def dft_inverse(a0, a_last, an, bn, length):
    """The span of ``length`` samples whose series is (a0, aN, an, bn); missing an, bn are zeros.

    Evaluated at the row's true length, not at the thesis's half resolution.
    """
    an, bn = np.asarray(an, dtype=float), np.asarray(bn, dtype=float)
    spectrum = np.zeros(an.shape[:-1] + (length // 2 + 1,), dtype=complex)
    spectrum[..., 0] = np.asarray(a0) * length
    count = an.shape[-1]
    spectrum[..., 1:1 + count] = (an - 1j * bn) * length / 2
    if length % 2 == 0 and length > 1:
        spectrum[..., length // 2] = np.asarray(a_last) * length
    return np.fft.irfft(spectrum, n=length, axis=-1)


# --- DCT (§7.2.2) ---------------------------------------------------------------------

def dct_forward(spans):
    """Orthonormal DCT-II (MATLAB ``dct``) of each span."""
    from scipy.fft import dct

    return dct(np.asarray(spans, dtype=float), type=2, norm="ortho", axis=-1)


def dct_inverse(coefficients, length):
    """Inverse orthonormal DCT; coefficients beyond those given are zeros."""
    from scipy.fft import idct

    coefficients = np.asarray(coefficients, dtype=float)
    full = np.zeros(coefficients.shape[:-1] + (length,))
    full[..., :coefficients.shape[-1]] = coefficients
    return idct(full, type=2, norm="ortho", axis=-1)


# --- DWT (§7.2.3) ---------------------------------------------------------------------

def dwt_level(length, wavelet=DEFAULT_WAVELET, level=DEFAULT_LEVEL):
    """The decomposition level used for a span: ``level`` capped to what its length allows.

    pywt.dwt_max_level: floor(log2(m / (filter length - 1))), 0 when m is shorter. Past
    it every coefficient feels the boundary and the count grows instead of halving.
    """
    import pywt

    return min(level, pywt.dwt_max_level(length, pywt.Wavelet(wavelet).dec_len))


def dwt_lengths(length, wavelet=DEFAULT_WAVELET, level=DEFAULT_LEVEL):
    """The thesis's lengths vector [len(A_J), len(D_J), ..., len(D_1), m] for a span of ``length``."""
    import pywt

    filter_length = pywt.Wavelet(wavelet).dec_len
    details = []
    current = length
    for _ in range(dwt_level(length, wavelet, level)):
        current = pywt.dwt_coeff_len(current, filter_length, WAVELET_MODE)
        details.append(current)
    return [details[-1] if details else length, *details[::-1], length]


def dwt_forward(spans, wavelet=DEFAULT_WAVELET, level=DEFAULT_LEVEL):
    """C = [A_J D_J ... D_1] of each span (pywt.wavedec, symmetric mode), J = dwt_level."""
    import pywt

    spans = np.asarray(spans, dtype=float)
    j = dwt_level(spans.shape[-1], wavelet, level)
    if j == 0:
        return spans.copy()
    return np.concatenate(pywt.wavedec(spans, wavelet, mode=WAVELET_MODE, level=j, axis=-1), axis=-1)


def dwt_inverse(coefficients, lengths, wavelet=DEFAULT_WAVELET):
    """The span from C and its lengths vector (MATLAB ``waverec(C, L, wavelet)``); dropped entries are zeros."""
    import pywt

    coefficients = np.asarray(coefficients, dtype=float)
    if len(lengths) == 2:
        return coefficients.copy()
    bands = np.split(coefficients, np.cumsum(lengths[:-2]), axis=-1)
    return pywt.waverec(bands, wavelet, mode=WAVELET_MODE, axis=-1)[..., :lengths[-1]]
