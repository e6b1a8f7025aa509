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

VANDER_BUDGET = 1 << 22   # basis values evaluated at once when decoding (32 MB)
FIT_BUDGET = 1 << 26      # basis values of one least-squares fit when encoding (512 MB)


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
    """Least-squares polynomial coefficients of each span.

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
        return np.linalg.lstsq(vander, spans.T, rcond=None)[0].T
    rows = np.atleast_2d(spans)
    xs = np.broadcast_to(np.atleast_2d(power_points(first, length, step)), rows.shape)
    fits = np.array([_power_fit(x, row, n) for x, row in zip(xs, rows)])
    return fits.reshape(spans.shape[:-1] + (n + 1,))


def _power_fit(x, row, n):
    """``polyfit`` of one row; rank warnings are the documented instability, not news. A degree
    whose powers of x overflow cannot be fitted at all: that is an error, not a row of NaN."""
    import warnings

    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore", np.exceptions.RankWarning)
        scale = np.abs(x).max() ** (2 * n)
        if n and not (np.isfinite(scale) and scale > 0):
            raise MzcError(f"the power basis cannot fit degree {n} on columns up to x = {x.max():g} (x^{2 * n} "
                           "leaves binary64; the thesis's basis is unstable past degree ~40): use --basis chebyshev "
                           "or a lower degree", field="degree")
        try:
            fit = np.polyfit(x, row, n)
        except np.linalg.LinAlgError:
            fit = np.full(n + 1, np.nan)
    if not np.isfinite(fit).all():
        raise MzcError(f"the power basis fit of degree {n} failed (its Vandermonde matrix is singular in binary64): "
                       "use --basis chebyshev or a lower degree", field="degree")
    return fit


def poly_inverse(coefficients, length, basis="chebyshev", first=1, step=1.0):
    """Evaluate the polynomials of ``poly_forward`` at the span's samples.

    Through the basis matrix (span x coefficients) while it holds at most VANDER_BUDGET values,
    the way every file so far decoded; beyond that by a recurrence over the coefficients
    (Clenshaw's for Chebyshev, Horner's for powers), whose memory is the output's, so no
    degree and length a file declares can ask for more than the grid it decodes to.
    """
    coefficients = np.asarray(coefficients, dtype=float)
    count = coefficients.shape[-1]
    with np.errstate(over="ignore", invalid="ignore"):
        if basis == "chebyshev":
            points = chebyshev_points(length)
            if length * count <= VANDER_BUDGET:
                return coefficients @ np.polynomial.chebyshev.chebvander(points, count - 1).T
            return np.polynomial.chebyshev.chebval(points, np.moveaxis(coefficients, -1, 0))
        x = power_points(first, length, step)
        if length * count <= VANDER_BUDGET:
            powers = np.arange(count)[::-1]
            return np.einsum("...mn,...n->...m", x[..., None] ** powers, coefficients)
        values = np.zeros(coefficients.shape[:-1] + (length,))
        for index in range(count):   # Horner, highest power first as the coefficients are stored
            values = values * x + coefficients[..., index:index + 1]
        return values


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
