"""The colour section of a grid: an (R, C, 3) uint8 image aligned with the nodes, coded by
pure functions over arrays (spec/colour.md gives every byte).

``encode_colour(rgb, mask, max_error=..., psnr=...)`` returns self-delimiting bytes (a container
appends them as a section; ``section_length`` says where they end), ``decode_colour(data, mask)``
the image, 0 at invalid nodes. With ``scale`` K > 1 the image is the grid's colours sampled K
times finer than the nodes of ``mask`` (``mzc.grid.fine_mask`` says which samples are valid),
coded the same way in a version 2 section, whose header adds K; K = 1 writes version 1. The
fine colours of a multi-chart grid (``charts``) are a version 3 section, version 2's layout, whose
valid samples lie in one chart each: a reader that knows no charts refuses it.

The encoder takes the reversible YCoCg-R colour transform, fills
invalid nodes with the harmonic fill of dwt2d (so no bits go on a jump at the mask's edge),
lifts each channel with dwt2d's CDF 9/7 in binary64 (lossy) or the integer LeGall 5/3
(lossless), quantises each band with a step in sixteenths of a level (chroma coarser than luma),
and codes the integers with dwt2d's contexts and rANS coder. The decoder's arithmetic is
integers or the binary64 lifting of spec/dwt2d.md: the same image on every machine. With
``max_error`` E (8-bit levels) a correction layer of residuals quantised with step 2E + 1 makes
|decoded - rgb| <= E hold at every valid node after rounding and clipping; E = 0 is lossless
(step 1 everywhere, the integer lifting being exactly reversible). With ``psnr`` the luma step
is searched so that the PSNR over the valid nodes' three channels meets the target.
"""

import struct
import zlib

import numpy as np

from mzc import elementary
from mzc.codecs.dwt2d import (
    CORRECTION_THRESHOLDS,
    SAME_SIZE,
    correction_model,
    decode_bands,
    encode_bands,
    encode_corrections,
    lifting,
)
from mzc.codecs.dwt2d import wavelet as w2
from mzc.errors import MzcError

MAGIC = b"mzcC"
VERSION = 1                               # colours at the nodes
FINE_VERSION = 2                          # colours sampled K times finer than the nodes: the header adds K
CHARTED_VERSION = 3                       # 2 on a multi-chart grid: no valid sample between two charts
FINE_HEADER = struct.Struct("<4sBIIBBBHHHBII")   # versions 2 and 3: version 1's with K after cols
HEADERS = {VERSION: struct.Struct("<4sBIIBBHHHBII"),   # magic, version, rows, cols, levels, transform, 3 steps,
           FINE_VERSION: FINE_HEADER, CHARTED_VERSION: FINE_HEADER}   # correction, length, crc32
LENGTH = 10                               # read_header's index of the payload's length
LEAD = struct.Struct("<4sB")              # magic and version: which header follows
CRC_BYTES = 4                             # the CRC-32 (last in the header) covers the header before it and the payload
UNIT = 16                                 # steps are written in sixteenths of a level
MAX_SIDE = 1 << 24                        # rows and columns the decoder accepts (far beyond any grid)
MAX_QUANTUM = 1 << 24                     # |q| beyond this cannot come from 8-bit colour: a damaged payload
MAX_CORRECTION_ERROR = 127                # 2E + 1 fits in a byte
COARSEST = 8                              # levels until the coarsest band is about 8 nodes across (as dwt2d)
CHROMA_RATIOS = (2.5, 2.0)                # Co and Cg steps over Y's: an error e in Co moves R and B by e/2,
                                          # in Cg G by e/2 and R, B by -e/2, so each weighs 1/6 and 1/4 of
                                          # Y's in the RGB squared error; the MSE-optimal steps grow as
                                          # 1/sqrt(weight) (2.45, 2)
ROUNDING = 4                              # encoder: quantise with floor(|c|/step + 0.4) (tenths)...
DEADZONE = 0.6                            # ...or, the 9/7's real coefficients, floor(|c|/step + 1 - 0.6)
ALPHAS = (1.5, 2.5, 4.0)                  # max_error: luma steps tried, times E; the smallest section wins
PSNR_SLOPE = 2.0                          # the squared error grows about as step**2
PSNR_GUESS = 4.0                          # psnr: the first step tried, in levels
LARGEST_STEP = 4095.0                     # a step above this one does not fit its 16-bit field
DEFAULT_PSNR = 36.0
STEP_FACTORS = ((177, 116, 63), (177, 116, 63), (256, 199, 116))   # H, V, D of levels 1..3, 256ths (band_steps)
BAND0_FACTOR = 248


# --------------------------------------------------------------------------- colour transform


def ycocg(rgb):
    """(Y, Co, Cg) int64 planes of an (R, C, 3) image by YCoCg-R: reversible in integers
    (Y in 0..255, Co and Cg in -255..255)."""
    r, g, b = (rgb[..., i].astype(np.int64) for i in range(3))
    co = r - b
    t = b + (co >> 1)
    cg = g - t
    return [t + (cg >> 1), co, cg]


def rgb_of(y, co, cg):
    """The (R, C, 3) int64 image of Y, Co, Cg planes: the exact inverse of ``ycocg``."""
    t = y - (cg >> 1)
    g = cg + t
    b = t - (co >> 1)
    return np.stack([b + co, g, b], axis=-1)


# --------------------------------------------------------------------------- integer 5/3 lifting


def split_integer(x):
    """(low, high) of one level of the reversible LeGall 5/3 along axis 0 of int64 ``x``
    (JPEG 2000's): d_k -= floor((s_k + s_k+1) / 2), then s_k += floor((d_k-1 + d_k + 2) / 4),
    whole-sample symmetric extension at the ends (lifting's neighbours)."""
    if len(x) == 1:
        return x.copy(), x[:0]
    even, odd = x[0::2].copy(), x[1::2].copy()
    odd -= (even[:len(odd)] + lifting.following(even, len(odd), False)) >> 1
    even += (lifting.preceding(odd, len(even), False) + lifting.extended(odd, len(even)) + 2) >> 2
    return even, odd


def merge_integer(low, high):
    """Inverse of ``split_integer``: the signal along axis 0 (the steps undone in reverse order)."""
    if not len(high):
        return low.copy()
    even, odd = low.copy(), high.copy()
    even -= (lifting.preceding(odd, len(even), False) + lifting.extended(odd, len(even)) + 2) >> 2
    odd += (even[:len(odd)] + lifting.following(even, len(odd), False)) >> 1
    x = np.empty((len(even) + len(odd),) + even.shape[1:], dtype=np.int64)
    x[0::2], x[1::2] = even, odd
    return x


def forward(plane, levels):
    """Integer bands [LL, (H, V, D) coarse to fine ...] of an int64 plane (dwt2d's layout)."""
    return lifting.pyramid(plane, lambda x, _wrap: split_integer(x), levels, False)


def inverse(bands):
    """The int64 plane of integer ``bands``: each level merges columns, then rows (lifting.inverse's order)."""
    low = bands[0]
    for h, v, d in bands[1:]:
        low = merge_integer(merge_integer(low, h).T, merge_integer(v, d).T).T
    return low


# --------------------------------------------------------------------------- quantisation


def band_steps(step, levels):
    """Every band's step (sixteenths, >= UNIT) from a channel's ``step``, that of the finest D band
    (the largest: so a step of 1 level is 1 in every band, lossless). The integer 5/3's synthesis
    gains g differ by band (measured on noise in each band alone: 1.08 for H and V of level 1,
    2.54 at level 2, 8.6 at 3, then 4x a level; D 0.52, 0.85, 2.5, then 4x; band 0 about
    0.55 * 4^L) and the MSE-optimal steps grow as 1/sqrt(g): so each band takes step times its
    factor in 256ths (STEP_FACTORS, halving a level past the third; band 0 BAND0_FACTOR / 2^L),
    in integers, so every decoder gets the same steps."""
    steps = [max(UNIT, (step * BAND0_FACTOR) >> (8 + levels))]
    for level in range(levels, 0, -1):
        steps += [max(UNIT, (step * level_factor(factors, level)) >> 8) for factors in STEP_FACTORS]
    return steps


def level_factor(factors, level):
    """A band's step factor in 256ths at ``level`` (1 the finest) from its first three levels'."""
    return factors[level - 1] if level <= len(factors) else factors[-1] >> (level - len(factors))


def quantise(band, step):
    """Integers floor(|c| 16 / step + ROUNDING/10) with c's sign, of an integer band (encoder only)."""
    magnitude = (np.abs(band) * (10 * UNIT) + ROUNDING * step) // (10 * step)
    return np.sign(band) * magnitude


def dequantise(q, step):
    """Integer coefficients of quantised ``q``: round(|q| step / 16) with q's sign."""
    return np.sign(q) * ((np.abs(q) * step + UNIT // 2) >> 4)


def reconstructed(qflat, steps, levels):
    """A channel's int64 plane from its quantised flat bands and their steps (sixteenths)."""
    return inverse(w2.unflatten([dequantise(q, s) for q, s in zip(qflat, steps)], levels))


class Integer53:
    """Transform 0: the reversible LeGall 5/3 on integers, band steps from its gains
    (``band_steps``): exact at step 1 (lossless), and all-integer."""

    number, wavelet = 0, "bior2.2"

    @staticmethod
    def analyse(plane, levels):
        """The flat integer bands [LL, H, V, D, ...] of an int64 plane."""
        return w2.flatten(forward(plane, levels))

    band_steps = staticmethod(band_steps)
    quantise = staticmethod(quantise)
    plane = staticmethod(reconstructed)


class Cdf97:
    """Transform 1: dwt2d 3.0's CDF 9/7 lifting in binary64 (spec/dwt2d.md; near-orthonormal, so
    every band of a channel takes the channel's step), the decoded plane rounded to integers.
    Measured at 36 dB against transform 0: 6-7% smaller on the fuze texture and the milk carton,
    24% on the generated height field."""

    number, wavelet = 1, "bior4.4"

    @staticmethod
    def analyse(plane, levels):
        """The flat real bands of an int64 plane."""
        return w2.flatten(lifting.forward(plane.astype(np.float64), "bior4.4", levels))

    @staticmethod
    def band_steps(step, levels):
        """The channel's step for every band."""
        return [step] * (1 + 3 * levels)

    @staticmethod
    def quantise(band, step):
        """dwt2d's dead-zone quantiser (encoder only) at ``step`` sixteenths."""
        return w2.quantise_band(np.abs(band), np.sign(band), step / UNIT, DEADZONE)

    @staticmethod
    def plane(qflat, steps, levels):
        """The int64 plane: q * (step / 16) in binary64, the inverse lifting, rounded to nearest (ties even)."""
        return np.rint(lifting.inverse(w2.dequantise(qflat, [s / UNIT for s in steps]), "bior4.4")).astype(np.int64)


TRANSFORMS = (Integer53, Cdf97)


# --------------------------------------------------------------------------- encoder


class Prepared:
    """An image ready to be coded at any steps: its three filled YCoCg-R channels, and their bands
    by each transform tried (taken once: the searches quantise them at every step they try)."""

    def __init__(self, rgb, mask, levels=None, scale=1, version=VERSION):
        rgb, self.mask = check_image(rgb, mask)
        self.scale, self.version = scale, version
        self.rgb = rgb.astype(np.int64)
        self.levels = w2.default_levels(self.mask.shape, COARSEST) if levels is None else levels
        self.planes = [filled(channel, self.mask) for channel in ycocg(rgb)]
        self.transformed = {}

    def bands(self, transform):
        """(relevance, each channel's flat bands with the irrelevant coefficients 0) by ``transform``."""
        if transform not in self.transformed:
            relevant = w2.flatten(lifting.relevance(self.mask, transform.wavelet, self.levels))
            self.transformed[transform] = relevant, [
                [np.where(r, band, 0) for band, r in zip(transform.analyse(plane, self.levels), relevant)]
                for plane in self.planes]
        return self.transformed[transform]

    def channel_steps(self, luma):
        """(Y, Co, Cg) steps in sixteenths for a luma step in levels (chroma coarser by CHROMA_RATIOS)."""
        return [snap_step(luma)] + [snap_step(luma * ratio) for ratio in CHROMA_RATIOS]

    def decoded(self, transform, steps):
        """(each channel's quantised bands, the decoded image: valid nodes clipped to 0..255) at ``steps``."""
        qflats, planes = [], []
        for bands, step in zip(self.bands(transform)[1], steps):
            per_band = transform.band_steps(step, self.levels)
            qflats.append([transform.quantise(band, s) for band, s in zip(bands, per_band)])
            planes.append(transform.plane(qflats[-1], per_band, self.levels))
        return qflats, clipped(rgb_of(*planes), self.mask)

    def squared_error(self, decoded):
        """The mean squared error over the valid nodes' three channels."""
        error = (decoded - self.rgb)[self.mask]
        return float(np.sum(error * error)) / max(error.size, 1)

    def section(self, transform, steps, max_error=None):
        """(section bytes, the image its decoder gets) by ``transform`` at ``steps``; with ``max_error``
        a correction layer of step 2E + 1 where the wavelet alone misses the bound."""
        from mzc.codecs.dwt2d.entropy import Encoder  # here: only the encoder needs constriction

        qflats, decoded = self.decoded(transform, steps)
        encoder = Encoder(same_size=SAME_SIZE)
        relevant = self.bands(transform)[0]
        for qflat, step in zip(qflats, steps):
            scaled = [s / UNIT for s in transform.band_steps(step, self.levels)]
            encode_bands([encoder] * len(qflat), qflat, relevant, scaled)
        correction = 0
        if max_error is not None and np.abs(decoded - self.rgb)[self.mask].max(initial=0) > max_error:
            correction = 2 * max_error + 1
            k = np.zeros(self.rgb.shape, dtype=np.int64)
            k[self.mask] = (self.rgb - decoded)[self.mask] + max_error   # floor((r + E) / C): |r - C k| <= E
            k //= correction
            for channel in range(3):
                encode_corrections(encoder, k[..., channel], self.mask)
            decoded = clipped(decoded + correction * k, self.mask)   # as the decoder adds them
        return section_bytes(self.mask.shape, self.version, self.scale, self.levels, transform.number, steps,
                             correction, encoder.finish()), decoded


def filled(channel, mask):
    """An int64 channel with invalid nodes replaced by dwt2d's harmonic fill of the valid ones, rounded."""
    return np.rint(w2.laplace_fill(channel.astype(np.float64), mask)).astype(np.int64)


def clipped(image, mask):
    """The decoded image: values clipped to 0..255 at valid nodes, 0 at the others."""
    return np.where(mask[..., None], np.clip(image, 0, 255), 0)


def snap_step(levels):
    """A step in levels as the integer sixteenths its field holds (1 to LARGEST_STEP levels), rounded
    down: the search's points between two sixteenths then land on the lower one, not on one it took."""
    return int(np.floor(min(max(levels, 1.0), LARGEST_STEP) * UNIT))


def check_image(rgb, mask):
    """(rgb as uint8, mask as bool) or an MzcError naming what does not fit."""
    rgb, mask = np.asarray(rgb), np.asarray(mask)
    if mask.ndim != 2 or mask.dtype != bool:
        raise MzcError(f"the mask must be a 2D bool array, not {mask.ndim}D {mask.dtype}", field="mask")
    if rgb.shape != mask.shape + (3,) or rgb.dtype != np.uint8:
        raise MzcError(f"colours must be uint8 of shape {mask.shape + (3,)}, not {rgb.dtype} {rgb.shape}",
                       field="colors")
    if not 1 <= min(mask.shape) <= max(mask.shape) <= MAX_SIDE:
        raise MzcError(f"a colour grid of {mask.shape[0]} x {mask.shape[1]} nodes (allowed 1..{MAX_SIDE} a side)",
                       field="colors")
    return rgb, mask


def encode_colour(rgb, mask, *, max_error=None, psnr=None, levels=None, scale=1, charts=None):
    """Section bytes of an (R, C, 3) uint8 image at the True nodes of ``mask``; with ``scale`` K > 1,
    of the ((R - 1) K + 1, (C - 1) K + 1, 3) image of colours K times finer than the nodes of the
    R x C ``mask``, at its valid samples (``mzc.grid.fine_mask``, of the grid's ``charts`` when it
    has them: version 3).

    ``max_error`` E (whole 8-bit levels, 0..127): |decoded - rgb| <= E at every valid node (E = 0:
    lossless); ``psnr`` (dB): the largest luma step found whose PSNR over the valid nodes meets it;
    neither: psnr DEFAULT_PSNR. ``levels``: of the wavelet, 0..12 (default: until the coarsest band
    is about COARSEST nodes across).
    """
    if levels is not None and not (isinstance(levels, int | np.integer) and 0 <= levels <= w2.MAX_LEVELS):
        raise MzcError(f"levels {levels} is not a whole number 0..{w2.MAX_LEVELS}", field="levels",
                       options=("levels",))
    if max_error is not None and psnr is not None:
        raise MzcError("give max_error or psnr, not both", field="max_error", options=("max_error", "psnr"))
    if max_error is not None and not (0 <= max_error <= MAX_CORRECTION_ERROR and float(max_error).is_integer()):
        raise MzcError(f"max_error {max_error} is not a whole number of levels 0..{MAX_CORRECTION_ERROR}",
                       field="max_error", options=("max_error",))
    target = DEFAULT_PSNR if psnr is None else float(psnr)
    if not 0 < target < 200:
        raise MzcError(f"psnr {psnr} is not in 0..200 dB", field="psnr", options=("psnr",))
    if scale != 1:
        from mzc.grid import fine_mask
        from mzc.limits import check_colour_scale

        mask = np.asarray(mask)
        scale = check_colour_scale(scale, *mask.shape, field="scale")
        mask = fine_mask(mask, scale, charts) if mask.ndim == 2 and mask.dtype == bool else mask   # else check_image
    version = VERSION if scale == 1 else FINE_VERSION if charts is None else CHARTED_VERSION
    prepared = Prepared(rgb, mask, levels, scale, version)
    if max_error is not None:
        return bounded_section(prepared, int(max_error))
    return psnr_section(prepared, target)


def bounded_section(prepared, max_error):
    """The smallest section of the 9/7 at the luma steps ALPHAS times E (measured: smaller than the
    5/3's at each of them, by 3-15%, on the fuze texture, the milk carton and the height field at E
    = 1..16); E = 0: transform 0 at step 1, lossless."""
    if not max_error:
        return prepared.section(Integer53, [UNIT] * 3, 0)[0]
    sections = [prepared.section(Cdf97, prepared.channel_steps(alpha * max_error), max_error)[0]
                for alpha in ALPHAS]
    return min(sections, key=len)


def psnr_section(prepared, target):
    """The section by the 9/7 at the largest luma step found whose PSNR meets ``target`` (w2.search_step
    on the squared error: 255^2 / 10^(target / 10), the power taken with mzc.elementary); the
    lossless one when even its smallest step misses the target."""
    limit = 255.0 ** 2 / elementary.exp(target / 10.0 * elementary.log(10.0))
    cost = lambda luma: prepared.squared_error(  # noqa: E731
        prepared.decoded(Cdf97, prepared.channel_steps(luma))[1])
    luma = w2.search_step(cost, limit, 1.0, LARGEST_STEP, PSNR_GUESS, PSNR_SLOPE, snap=lambda x: snap_step(x) / UNIT)
    section, decoded = prepared.section(Cdf97, prepared.channel_steps(luma))
    return section if prepared.squared_error(decoded) <= limit else bounded_section(prepared, 0)


def section_bytes(shape, version, scale, levels, transform, steps, correction, payload):
    """The header (with the CRC-32 of it and the payload) and the payload: version 1 (at ``scale`` 1)
    byte for byte as before colour scales, else ``version`` 2 or 3 with the scale after the columns."""
    fields = (levels, transform, *steps, correction, len(payload), 0)
    head = (HEADERS[VERSION].pack(MAGIC, VERSION, *shape, *fields) if version == VERSION
            else HEADERS[version].pack(MAGIC, version, *shape, scale, *fields))
    crc = zlib.crc32(payload, zlib.crc32(head[:-CRC_BYTES]))
    return head[:-CRC_BYTES] + struct.pack("<I", crc) + payload


# --------------------------------------------------------------------------- decoder


def section_length(data, source="<bytes>"):
    """The length of the colour section at the start of ``data`` (a container's next section follows)."""
    fields = read_header(data, source)
    return HEADERS[fields[1]].size + fields[LENGTH]


def read_header(data, source):
    """The header's fields (magic and version checked) in version 1's order, then the colour scale
    (versions 2 and 3's field after the columns; 1 in version 1), or an MzcError."""
    magic, version = LEAD.unpack_from(data) if len(data) >= LEAD.size else (bytes(data[:4]), None)
    if magic != MAGIC:
        raise MzcError(f"not a colour section (starts {bytes(magic)!r}, not {MAGIC!r})", source=source,
                       field="colour")
    if version not in HEADERS:
        raise MzcError(f"colour section version {version} (this mzc reads {', '.join(map(str, HEADERS))})",
                       source=source, field="colour")
    header = HEADERS[version]
    if len(data) < header.size:
        raise MzcError(f"colour section of {len(data)} bytes ends inside its {header.size}-byte header",
                       source=source, field="colour")
    fields = header.unpack_from(data)
    return fields + (1,) if version == VERSION else fields[:4] + fields[5:] + fields[4:5]


def decode_colour(data, mask, source="<bytes>", charts=None):
    """The (R, C, 3) uint8 image of a colour section that spans ``data``, 0 at invalid nodes (of
    a multi-chart grid, ``charts`` its charts: version 3); any damage, a mask of another shape, or
    a section of another kind of grid raises an MzcError."""
    from mzc.codecs.dwt2d.entropy import Decoder
    from mzc.grid import fine_mask, fine_shape

    data = bytes(data)
    _magic, version, rows, cols, levels, number, *rest = read_header(data, source)
    steps, (correction, length, crc, scale) = rest[:3], rest[3:]
    mask = np.asarray(mask, dtype=bool)
    fault = charts_fault(version, charts) or scale_fault(scale, version, mask.shape) or section_fault(
        data, HEADERS[version].size, (rows, cols), fine_shape(mask.shape, scale), levels, number, steps, length, crc)
    if fault:
        raise MzcError(fault, source=source, field="colour")
    if scale > 1:
        mask = fine_mask(mask, scale, charts)
    transform = TRANSFORMS[number]
    decoder = Decoder(data[HEADERS[version].size:], source, SAME_SIZE)
    relevant = w2.flatten(lifting.relevance(mask, transform.wavelet, levels))
    planes = []
    for step in steps:
        per_band = transform.band_steps(step, levels)
        qflat = decode_bands([decoder] * len(relevant), relevant, [s / UNIT for s in per_band])
        if max(int(np.abs(q).max(initial=0)) for q in qflat) > MAX_QUANTUM:
            raise MzcError("a quantised coefficient is far outside 8-bit colour", source=source, field="colour")
        planes.append(transform.plane(qflat, per_band, levels))
    image = clipped(rgb_of(*planes), mask)
    if correction:
        k = np.stack([decoder.read_rows(mask, np.zeros(mask.shape), CORRECTION_THRESHOLDS, correction_model(0))
                      for _ in range(3)], axis=-1)
        if np.abs(k).max(initial=0) > 255:
            raise MzcError("a correction is larger than 255 levels", source=source, field="colour")
        image = clipped(image + correction * k, mask)
    decoder.check_end()
    return image.astype(np.uint8)


def charts_fault(version, charts):
    """What is wrong with a section's version on a grid with or without ``charts`` (None when
    nothing is): version 3, colours finer than the nodes of a multi-chart grid, on such a grid
    alone, and no version 2 on it (its samples between the charts would be valid)."""
    if version == CHARTED_VERSION and charts is None:
        return "a colour section of version 3 belongs to a multi-chart grid, and this grid has no charts"
    if version == FINE_VERSION and charts is not None:
        return "a colour section of version 2 belongs to a grid without charts, and this grid has charts"
    return None


def scale_fault(scale, version, mask_shape):
    """What is wrong with a version 2 or 3 section's scale (None when nothing is): 2..MAX_COLOUR_SCALE, its
    image within the grid limits (checked before the shapes are compared, and anything allocated)."""
    from mzc.limits import MAX_COLOUR_SCALE, check_colour_scale

    if version == VERSION:
        return None
    if not 2 <= scale <= MAX_COLOUR_SCALE:
        return f"colour scale {scale} (allowed 2..{MAX_COLOUR_SCALE})"
    try:
        check_colour_scale(scale, *mask_shape)
    except MzcError as error:
        return f"colour scale {scale}: {error.message}"
    return None


def section_fault(data, header_size, shape, mask_shape, levels, transform, steps, length, crc):
    """What is wrong with a section's header fields and length (None when nothing is)."""
    if tuple(mask_shape) != shape:
        return f"the section's image is {shape[0]} x {shape[1]} samples, the mask's {mask_shape}"
    if not 1 <= min(shape) <= max(shape) <= MAX_SIDE:
        return f"a colour grid of {shape[0]} x {shape[1]} nodes (allowed 1..{MAX_SIDE} a side)"
    if levels > w2.MAX_LEVELS:
        return f"{levels} wavelet levels (allowed 0..{w2.MAX_LEVELS})"
    if transform >= len(TRANSFORMS):
        return f"transform {transform} (this mzc knows 0..{len(TRANSFORMS) - 1})"
    if min(steps) < UNIT:
        return f"a step of {min(steps)}/16 level is below 1 level"
    if len(data) != header_size + length:
        return f"the section declares {header_size + length} bytes and has {len(data)}"
    if zlib.crc32(data[header_size:], zlib.crc32(data[:header_size - CRC_BYTES])) != crc:
        return "the colour section's CRC-32 does not match (damaged bytes)"
    return None
