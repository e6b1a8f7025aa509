"""The wavelet z-grid codec (``mzc-dwt2d 10.0``, 8.0 in a tighter container with short table records; 8.0, 7.0
with the mask as predicted flips; 7.0: the fields of
3.1, 3.2 with a raster's crs and raster lines, 4.0 with charts and 6.0 for a raster of integers that decodes
to integers in a binary container; those are read, and written as the tiles of 5.0; 3.0 and 2.0 are read;
extension ``.mzw2``): see spec/dwt2d.md.

Text header (grid fields with the projection, wavelet, levels, steps, slope limit,
correction step), a ``data`` line, then a binary payload: the validity mask as row spans (8.0: as
predicted flips through adaptive binary models, mzc.codecs.dwt2d.flips),
the quantised wavelet bands (the transform of the version, ``wavelet2d.TRANSFORMS``;
detail steps scaled up where the surface leans from the node lines, magnitudes and signs
each with their own contexts), and an optional correction layer of residuals that makes
``max_error`` hold at every valid node of the decoder's own reconstruction. All integers
are entropy coded by mzc.codecs.dwt2d.entropy (magnitude classes through rANS, one model per context),
and decoded by the C row loop of mzc.codecs.dwt2d._rows. A grid larger than one tile is coded as
``mzc-dwt2d 5.0``, independent tiles each a file of this kind (mzc.codecs.dwt2d.tiles).
"""
import functools

import numpy as np

from mzc import elementary
from mzc.codecs.base import Codec, Option
from mzc.codecs.dwt2d import _rows, compact, flips
from mzc.codecs.dwt2d import wavelet as w2
from mzc.errors import MzcError
from mzc.formats.header import (
    file_bytes,
    file_version,
    format_number,
    grid_header_lines,
    magic_line,
    read_grid_fields,
    read_header,
)
from mzc.georef import is_geographic
from mzc.grid import MAX_CHARTS, ZGrid
from mzc.limits import MAX_MAGNITUDE

KIND = "dwt2d"
VERSION = (3, 1)             # every grid not read from a raster; 3.0 (no crc32 line) and 2.0 (planar, periodised
                             # transform) are still read
PROJECTED_VERSION = (3, 1)
GEOREFERENCED_VERSION = (3, 2)   # 3.1 with the crs and raster lines of a grid read from a raster
CHARTED_VERSION = (4, 0)     # 3.1 with the charts line of a multi-chart grid (its charts side by side)
TILED_VERSION = (5, 0)       # a grid in independent tiles, each a 3.1 file (mzc.codecs.dwt2d.tiles)
ROUNDED_TILED_VERSION = (5, 1)   # 5.0 with ``rounding integer``: its tiles are 6.0 files of a raster's integers
COLOURED_TILED_VERSION = (11, 0)   # 5.0 whose tiles are whole 10.x files, each with its block's colour section
                                   # (a 5.x reader would refuse the tiles: a new major)
ROUNDED_VERSION = (6, 0)     # 4.0 with the crs and raster lines and ``rounding integer``: a raster of integers
                             # coded with max_error, whose decoded values are rounded to integers (a new major:
                             # a 4.0 reader, ignoring the line, would decode other values)
COMPACT_VERSION = (7, 0)     # the fields of 3.x-6.0 in binary, tagged sections with CRC-32s (mzc.codecs.dwt2d.compact);
                             # tiles of 5.0 stay 3.1 files
FLIPS_VERSION = (8, 0)       # every grid coded whole: 7.0 with the source_vertices field and the mask as predicted
                             # flips (mzc.codecs.dwt2d.flips)
PROGRESSIVE_VERSION = (9, 0)   # opt-in (``progressive``): 8.0 in sections, the mask and band 0, then one detail level
                               # each, coarsest first, so that a prefix of whole sections decodes (coarser)
TIGHT_VERSION = (10, 0)      # every grid coded whole by default: 8.0 in one section with one CRC-32, its header fields
                             # without counts where implied, its tables in short records (compact.tight_bytes,
                             # entropy.choose_short_records)
BAND_MODELS_VERSION = (10, 1)   # 10.0 with ``band_models 1``: each detail band its own contexts' models, written
                                # where that makes the file smaller (a large DEM's, by 4-6%)
GEOREF_SINCE = dict([GEOREFERENCED_VERSION, TILED_VERSION, ROUNDED_VERSION, COMPACT_VERSION, FLIPS_VERSION,
                     PROGRESSIVE_VERSION, TIGHT_VERSION, COLOURED_TILED_VERSION])   # major -> first minor
                                                                                    # with crs, raster
ROUNDING = "integer"         # the one value of the rounding line
ROUNDING_ULPS = 16           # the coded bound stays this many units in the last place of the largest value below
                             # floor(E) + 1/2, more than the float noise of a decoded value
OLDEST_MAJOR = 2             # 1.x were drafts
CHECKSUM_SINCE = {3: 1, 4: 0, 5: 0, 6: 0, 11: 0}   # the crc32 line is required from 3.1 on (text headers)
CODER = "rans-signs-2"     # 2.0 names it on a required line; in 3.0 the version implies it
# detail contexts, shared by every detail band: activity of parent, siblings, two rows above
THRESHOLDS = (0.5, 1.0, 1.5, 3.0, 5.0, 8.0, 14.0, 24.0, 40.0, 70.0)
CONTEXTS = len(THRESHOLDS) + 1
# detail signs: per orientation (H, V, D) the weights of the sign above, the parent's sign and
# (odd columns) the signs left and right in a predicted sign. Measured on the faces: the
# coefficient above has the opposite sign 80-87% of the time in H bands, the same 65-70% in
# V bands; the one to the left the same 68-81% in H, the opposite 80-85% in V.
SIGN_WEIGHTS = ((-2, 1, 2), (2, 1, -2), (-1, 0, 0))
SIGN_CONTEXTS = 4   # per column parity
CORRECTION_THRESHOLDS = (0.25, 1.0, 2.0)   # correction layer: 4 contexts from the rows above
DEFAULT_WAVELET = "bior4.4"
ALPHAS = (3.2, 4.8, 7.2)   # max_error: wavelet step = alpha * E (the best alpha grows from 3 to 8 as E
                           # goes from 0.05 to 2 mm on the faces), the smallest file wins...
ALPHA_SLACK = 0.01         # ...but a smaller alpha within 1% of it is taken for its lower RMS error
UNIT_RATIO = 100.0          # heights spanning more than 100x the width: not one unit (check_shared_unit)
GEOGRAPHIC_RATIO = 10.0     # within lon/lat bounds at spacings under GEOGRAPHIC_STEP, 10x already
GEOGRAPHIC_STEP = 0.1
SLOPE_LIMIT = 2.0          # steps grow as 1/sqrt(cos(lean)) up to 2x (76 degrees); 1 = equal steps
APPROXIMATION_GAIN = 0.7   # band 0's step over the finest detail step (measured: 0.5-3% smaller files)
LEVEL_RATIO = 0.9          # each coarser detail level's step over the next finer one's (measured: 0.4-3.6%)
TARGETS = ("max_error", "rmse", "size")   # at most one of them says what the encoder aims at...
COLOUR_TARGETS = ("colour_psnr", "colour_max_error")   # ...and at most one of these, for the colours...
DEFAULT_COLOUR_PSNR = 36.0   # ...whose default PSNR keeps the colour RMS error near 4 levels
DEFAULT_RMSE_SPACING = 0.1   # ...and without one, rmse is a tenth of the grid's node spacing (default_rmse)
DEADZONE = 0.5             # encoder-only rounding offset (floor(|c|/step + 1 - DEADZONE)): to the nearest, and
RDO_LAMBDA = 0.05          # lowered_toward_zero's lambda in squared steps per bit then moves some toward zero
                           # (1.2-2.7% smaller files than 0.6 without it; 0.55 or lambda 0.03-0.1 in between)
RMS_GUESS = 20.0           # rmse: the search's first step, times the target (the faces' steps are 5-116 times
                           # their targets of 0.01-0.64 mm, the DEMs' 33-34 times)...
RMS_SLOPE = 0.6            # ...and their RMS error grows about as step**0.5-0.6 near them (the DEMs' as step)
SIZE_GUESS = 100.0         # size: the first step is 1/100 of the height range, and the file grows about
SIZE_SLOPE = 0.6           # as (1/step)**0.6 (f18 and the DEMs at 1.5-60 KB)
FINEST_MARGIN = 1000.0     # the searches' smallest step quantises the largest coefficient to MAX_QUANTUM / 1000

# model ids (the order of first use in the payload)
MASK_COUNT, MASK_SAME, MASK_NEW, APPROXIMATION = 0, 1, 2, 3
FIRST_DETAIL = 4


def detail_model(context, band=1, band_models=False):
    """Model id of a detail context of band ``band`` (1..3L). Every detail band shares band 1's models
    (on a face: 2.5-4% smaller files than one set per band, whose tables cost more than their sharper
    statistics save), but in a file with ``band_models`` (10.1: a large DEM's, 4-6% smaller), where
    band b >= 2 has its own, after the chart models."""
    if not band_models or band == 1:
        return FIRST_DETAIL + context
    return chart_model(CHART_FIELDS) + CONTEXTS * (band - 2) + context


def sign_model(context):
    """Model id of a detail sign context, 0..7 (after the detail models)."""
    return FIRST_DETAIL + CONTEXTS + context


def correction_model(context=0):
    """Model id of the correction layer's context (after the sign models)."""
    return FIRST_DETAIL + CONTEXTS + 2 * SIGN_CONTEXTS + context


def chart_model(field):
    """Model id of a chart record's field 0..6 (4.0; after the correction models)."""
    return correction_model(4) + field


CHART_FIELDS = 7   # a chart record's fields (encode_charts), each with its model
# the detail, sign and correction contexts are each mixed within a row: one class count each
SAME_SIZE = (range(detail_model(0), detail_model(CONTEXTS)), range(sign_model(0), sign_model(2 * SIGN_CONTEXTS)),
             range(correction_model(0), correction_model(4)))


def shared_detail_models(models):
    """Model ids of a file with band models (detail_model) as a file without them numbers them: each band's
    own detail models onto band 1's."""
    first_own = detail_model(0, 2, True)
    return np.where(models >= first_own, FIRST_DETAIL + (models - first_own) % CONTEXTS, models)


def same_size(bands=0, band_models=False):
    """SAME_SIZE, and with ``band_models`` the group of each of the ``bands`` detail bands' own models."""
    if not band_models:
        return SAME_SIZE
    return SAME_SIZE + tuple(range(detail_model(0, band, True), detail_model(CONTEXTS, band, True))
                             for band in range(2, bands + 1))


# --------------------------------------------------------------------------- mask


def encode_mask(encoder, valid):
    """Span counts (as change from the row above), then rows whose count did not change as
    moves of each flip from the row above, then the other rows as gaps between flips."""
    transitions = flips.row_flips(valid)
    counts = np.array([len(t) // 2 for t in transitions])
    encoder.add(MASK_COUNT, np.diff(counts, prepend=0))
    same, new = [], []
    previous = np.zeros(0, dtype=np.int64)
    for row in transitions:
        if len(row) == len(previous):
            same.append(row - previous)
        else:
            new.append(np.diff(row, prepend=-1) - 1)
        previous = row
    encoder.add(MASK_SAME, np.concatenate(same or [[]]))
    encoder.add(MASK_NEW, np.concatenate(new or [[]]))


def decode_mask(decoder, rows, cols):
    """The validity mask (rows x cols) from the payload; refuses impossible spans."""
    counts = np.cumsum(decoder.read(MASK_COUNT, rows))
    if counts.min() < 0 or counts.max() > (cols + 1) // 2:
        raise decoder.error(f"a mask row has a span count outside 0..{(cols + 1) // 2}")
    lengths = 2 * counts
    unchanged = lengths == np.concatenate([[0], lengths[:-1]])
    same = decoder.read(MASK_SAME, int(lengths[unchanged].sum()))
    new = decoder.read(MASK_NEW, int(lengths[~unchanged].sum()))
    valid = np.zeros((rows, cols), dtype=bool)
    bad = _rows.fill_spans(lengths, unchanged, same, new, rows, cols, valid)
    if bad >= 0:
        raise decoder.error(f"mask row {bad + 1} has spans outside the row or out of order")
    return valid


# --------------------------------------------------------------------------- bands


def parent_map(flat, index, shape):
    """The parent of every coefficient of detail band ``index`` (of ``shape``; same orientation, one
    level coarser in ``flat``, at (r div 2, c div 2) clipped to its shape); zeros at the coarsest
    level and under an empty parent band."""
    parent = flat[index - 3] if index > 3 else None
    if parent is None or parent.size == 0:   # the coarsest level, or a parent band with no rows or columns
        return np.zeros(shape, dtype=np.int64)
    r = np.minimum(np.arange(shape[0]) // 2, parent.shape[0] - 1)
    c = np.minimum(np.arange(shape[1]) // 2, parent.shape[1] - 1)
    return parent.take(r, axis=0).take(c, axis=1)   # 5x faster than parent[np.ix_(r, c)]


def activity(flat, index, steps, parent):
    """Activity of every coefficient of detail band ``index`` from the other bands already coded.

    |parent| (``parent``: its parent_map, in this band's step units) plus |q| of the earlier
    orientations of the same level at the same place (0 where the place lies outside them: in
    dwt2d 3.0 the bands of one level may differ by a row or a column).
    """
    active = np.abs(parent) * (steps[index - 3] / steps[index] if index > 3 else 0.0)
    orientation = (index - 1) % 3
    for sibling in range(index - orientation, index):
        active += np.abs(cropped(flat[sibling], active.shape))
    return active


def cropped(values, shape):
    """``values`` cut or zero-padded at the bottom and right to ``shape``."""
    out = np.zeros(shape, dtype=values.dtype)
    rows, cols = min(shape[0], values.shape[0]), min(shape[1], values.shape[1])
    out[:rows, :cols] = values[:rows, :cols]
    return out


def sign_prediction(above, parent, side, orientation, odd):
    """(sign context 0..7, predicted sign +-1, or 0 for none) of coefficients from the signs of
    the coefficient above, the parent and (odd columns) the sum ``side`` of the signs left and
    right: the weighted sum's size (contexts 4..7 in odd columns) and sign."""
    weight_above, weight_parent, weight_side = SIGN_WEIGHTS[orientation]
    score = weight_above * np.sign(above) + weight_parent * np.sign(parent) + weight_side * side
    return np.minimum(np.abs(score), SIGN_CONTEXTS - 1) + SIGN_CONTEXTS * odd, np.sign(score)


def sign_bits(values, predicted):
    """1 where a nonzero value's sign is not the predicted one (+ when none is predicted)."""
    return (np.sign(values) != np.where(predicted == 0, 1, predicted)).astype(np.int64)


def neighbours(above, above2):
    """Causal activity from the row above (up, and half of up-left and up-right) and half the row two above."""
    n = np.abs(above).astype(np.float64)
    out = n.copy()
    out[..., 1:] += 0.5 * n[..., :-1]
    out[..., :-1] += 0.5 * n[..., 1:]
    return out + 0.5 * np.abs(above2)


def beside(values):
    """At odd columns the sum of the values left and right (even columns, coded first in a
    row); 0 at even columns. Works on one row or on a whole band."""
    values = np.asarray(values, dtype=np.float64)
    out = np.zeros(values.shape)
    cols = values.shape[-1]
    out[..., 1::2] += values[..., 0:2 * (cols // 2):2]
    right = (cols - 1) // 2
    out[..., 1:2 * right:2] += values[..., 2:2 * right + 1:2]
    return out


def shifted_down(band, rows):
    """``band`` moved down by ``rows`` rows, zeros coming in at the top: each node sees the
    node that many rows above it."""
    out = np.zeros_like(band)
    out[rows:] = band[: max(band.shape[0] - rows, 0)]
    return out


def contexts(band, active, thresholds=THRESHOLDS):
    """Context of every coefficient of a whole band, from its activity, the rows above and (odd
    columns) the coefficients left and right."""
    return np.digitize(active + neighbours(shifted_down(band, 1), shifted_down(band, 2)) + beside(np.abs(band)),
                       thresholds)


def pass_index(rows, cols):
    """The pass of each cell: row by row, its even columns (2r) then its odd ones (2r + 1)."""
    return 2 * rows + cols % 2


def row_order(where, context):
    """(rows, cols, contexts) of the True cells of ``where``: row by row, even columns then odd
    ones, by context, left to right (np.nonzero lists them left to right already, so one stable
    sort by pass and context does it: a 4-key lexsort took a third of an encode's entropy coding)."""
    rows, cols = np.nonzero(where)
    ks = context[rows, cols]
    order = stable_order(pass_index(rows, cols) * (ks.max(initial=0) + 1) + ks)
    return rows[order], cols[order], ks[order]


def stable_order(keys):
    """np.argsort(keys, kind="stable") of integer keys >= 0, taken as 16-bit integers where
    they fit, which numpy sorts by radix (3.4x faster on a face's bands). A stable sort has
    one order, so it is the same."""
    if keys.size and keys.max() < 1 << 16:
        keys = keys.astype(np.uint16)
    return np.argsort(keys, kind="stable")


CHART_VIEWS = ("+z", "-z", "+x", "-x", "+y", "-y")   # a chart record's view, by number


def encode_charts(encoder, charts):
    """A multi-chart grid's chart records (4.0), field by field: each chart's view number, then
    ROW0, COL0 (each the change from the chart before), ROWS, COLS, I0, J0."""
    records = np.array([[CHART_VIEWS.index(c.view), c.row0, c.col0, c.rows, c.cols, c.i0, c.j0] for c in charts],
                       dtype=np.int64)
    records[1:, 1:3] -= records[:-1, 1:3].copy()
    for field in range(CHART_FIELDS):
        encoder.add(chart_model(field), records[:, field])


def decode_charts(decoder, count):
    """The ``count`` Charts of ``encode_charts``' records (the ZGrid checks where they lie)."""
    from mzc.grid import Chart

    records = np.stack([decoder.read(chart_model(field), count) for field in range(CHART_FIELDS)], axis=1)
    if ((records[:, 0] < 0) | (records[:, 0] >= len(CHART_VIEWS))).any():   # a negative one indexed from the end
        raise decoder.error("a chart's view number is not 0..5")
    records[:, 1:3] = np.cumsum(records[:, 1:3], axis=0)
    try:
        return tuple(Chart(CHART_VIEWS[record[0]], *(int(v) for v in record[1:])) for record in records)
    except MzcError as error:
        raise decoder.error(error.message) from None


def encode_corrections(encoder, k, valid):
    """Correction integers (a grid, 0 at invalid nodes) row by row in two passes (even, odd
    columns), by context of the rows above and (odd columns) the neighbours beside."""
    rows, cols, ks = row_order(valid, contexts(k, np.zeros(k.shape), CORRECTION_THRESHOLDS))
    encoder.add(correction_model(ks), k[rows, cols])


def band_level(index):
    """The level of band ``index`` of a flat list: 0 for the approximation, then 1 for the coarsest
    detail level's three bands, 2 for the next finer ones', ... (9.0's section of it)."""
    return (index + 2) // 3


def encode_bands(encoders, qflat, relevant, steps, band_models=False):
    """The approximation as planar differences, then each detail band row by row, each row in
    two passes (even columns, odd columns): the pass's magnitudes by context (``band_models``: the
    band's own models, detail_model), then the signs of its nonzero values left to right; each
    band's integers to ``encoders[band_level(index)]`` (8.0: one encoder for all of them)."""
    encoders[0].add(APPROXIMATION, np.diff(np.diff(qflat[0], axis=0, prepend=0), axis=1, prepend=0))
    for index in range(1, len(qflat)):
        band = qflat[index]
        parent = parent_map(qflat, index, band.shape)
        rows, cols, ks = row_order(relevant[index], contexts(band, activity(qflat, index, steps, parent)))
        odd = np.broadcast_to(np.arange(band.shape[1]) % 2, band.shape)
        sign_context, predicted = sign_prediction(shifted_down(band, 1), parent,
                                                  beside(np.sign(band)), (index - 1) % 3, odd)
        signed_rows, signed_cols = np.nonzero(band)
        # each pass's magnitudes (in row_order's order), then its signs (left to right, as np.nonzero lists them)
        order = stable_order(np.concatenate([2 * pass_index(rows, cols), 2 * pass_index(signed_rows, signed_cols) + 1]))
        models = np.concatenate([detail_model(ks, index, band_models),
                                 sign_model(sign_context[signed_rows, signed_cols])])
        values = np.concatenate([np.abs(band[rows, cols]),
                                 sign_bits(band[signed_rows, signed_cols], predicted[signed_rows, signed_cols])])
        encoders[band_level(index)].add(models[order], values[order], signed=False)


def decode_bands(decoders, relevant, steps, band_models=False):
    """Inverse of encode_bands: the flat list of integer bands, those of the levels ``decoders``
    does not reach zero (a prefix of a 9.0 file, or ``read``'s ``wanted``)."""
    residual = decoders[0].read(APPROXIMATION, relevant[0].size).reshape(relevant[0].shape)
    qflat = [np.cumsum(np.cumsum(residual, axis=0), axis=1)]
    for index in range(1, len(relevant)):
        if band_level(index) >= len(decoders):
            qflat.append(np.zeros(relevant[index].shape, dtype=np.int64))
            continue
        parent = parent_map(qflat, index, relevant[index].shape)
        band = decoders[band_level(index)].read_rows(
            relevant[index], activity(qflat, index, steps, parent), THRESHOLDS, detail_model(0, index, band_models),
            signs=(parent, SIGN_WEIGHTS[(index - 1) % 3], sign_model(0), SIGN_CONTEXTS))
        qflat.append(band)
    return qflat


# --------------------------------------------------------------------------- encoder


def lowered_toward_zero(qflat, magnitudes, steps, relevant, written):
    """Rate-distortion optimised quantisation of the detail bands of ``qflat`` (changed in place):
    each nonzero q moves one toward zero where that lowers J = D + RDO_LAMBDA R, D the squared
    error in units of its step (``steps``, one per band or per coefficient), so one lambda holds
    for every band and slope factor, and R the bits of its magnitude class in its context, the
    raw bits below its leading one and, when it becomes 0, its sign. The classes' bits come
    from their counts in each context over the bands as quantised (``written``: the steps
    line's per band, as the contexts see them); a greedy pass on those contexts, vectorised,
    as a trellis would need a row loop. The decoder reconstructs q * step as ever: measured on
    the 13 faces (benchmarks/encoder_gains.py), with rounding to the nearest, 1.2-2.7% fewer
    bytes at equal whole-surface RMS."""
    from mzc.codecs.dwt2d.entropy import MAX_CLASSES, classes

    ks = [contexts(qflat[i], activity(qflat, i, written, parent_map(qflat, i, qflat[i].shape)))
          for i in range(1, len(qflat))]
    cls = [classes(q) for q in qflat[1:]]
    counts = np.bincount(np.concatenate([(k * MAX_CLASSES + c)[r] for k, c, r in zip(ks, cls, relevant[1:])]),
                         minlength=CONTEXTS * MAX_CLASSES).reshape(CONTEXTS, MAX_CLASSES) + 0.5
    bits = -elementary.log2(counts / counts.sum(axis=1, keepdims=True)) + np.maximum(np.arange(MAX_CLASSES) - 1, 0)
    bits[:, 1:] += 1.0   # a nonzero value's sign
    for index, k, c in zip(range(1, len(qflat)), ks, cls):
        q = qflat[index].reshape(-1)   # a view: changed in place
        at = np.flatnonzero(q)
        size, k, c = np.abs(q[at]), k.reshape(-1)[at], c.reshape(-1)[at]
        saved = bits[k, c] - bits[k, classes(size - 1)]
        x = magnitudes[index].reshape(-1)[at] / np.broadcast_to(steps[index], qflat[index].shape).reshape(-1)[at]
        move = at[2.0 * (x - size) + 1.0 < RDO_LAMBDA * saved]   # (x - (m - 1))^2 - (x - m)^2 = 2 (x - m) + 1
        q[move] -= np.sign(q[move])


class Prepared:
    """Everything about one grid that does not depend on the steps: mask, fill, transform (and
    each band's magnitudes and signs, for quantising it at every step the rate control tries;
    the magnitude is 0 where the coefficient is not relevant, so it quantises to the 0 that
    is never coded)."""

    def __init__(self, grid, wavelet, levels, slope_limit, compact=True, colour=None, surface=None):
        self.surface = grid if surface is None else surface   # whose surface the rmse target measures (surface_terms)
        self.compact = compact   # 8.0 (or the container version given: 7.0 or 9.0), else the text header of 3.x,
                                 # 4.0, 6.0 (a tile of a 5.0 file)
        self.colour = colour     # (target line, colour section bytes) of a 7.0 file of a grid with colours
        self.transform = w2.TRANSFORMS[VERSION[0]]
        if np.isinf(grid.z).any():
            raise MzcError("the grid holds infinite heights", field="z")
        self.grid, self.wavelet, self.slope_limit = grid, wavelet, slope_limit
        self.vertical = is_geographic(grid)   # x, y in degrees: errors are heights alone (vertical_terms)
        self.valid = grid.valid
        self.levels = w2.default_levels(grid.shape, self.transform.coarsest) if levels is None else int(levels)
        self.geometry = w2.Geometry.of(grid.d1, grid.d2, grid.origin, grid.shape, grid.projection, grid.radius)
        self.filled = w2.smooth_fill(grid.z, self.valid, self.geometry.periodic)
        periodic = self.geometry.periodic
        self.bands = w2.flatten(self.transform.forward(self.filled, wavelet, self.levels, periodic))
        self.relevant = w2.flatten(self.transform.relevance(self.valid, wavelet, self.levels, periodic))
        self.magnitudes = [np.where(relevant, np.abs(b), 0.0) for b, relevant in zip(self.bands, self.relevant)]
        self.signs = [np.sign(b) for b in self.bands]

    @functools.cached_property
    def surface_terms(self):
        """(the valid heights, the weight a*cos(t) of each one's squared error, the area sum of
        a/cos(t)) of surface_rms, from the lean t of the surface from each node's line and its
        metric area a: only the rmse target needs them. On a geographic grid, weights of 1 over
        the node count: its RMS error is the vertical one, as a DEM's accuracy is stated. The lean and
        area are ``surface``'s: the grid's own, or the rebuilt surface of a residual (mzc.prior), whose
        values are not the surface's heights."""
        from mzc.ops.triangulation import jump_edges

        if self.vertical:
            heights = self.grid.z[self.valid]
            return heights, np.ones(heights.size), float(heights.size)
        surface, geometry, filled = self.surface, self.geometry, self.filled
        if surface is not self.grid:
            geometry = w2.Geometry.of(surface.d1, surface.d2, surface.origin, surface.shape, surface.projection,
                                      surface.radius)
            filled = w2.smooth_fill(surface.z, self.valid, geometry.periodic)
        lean, metric = w2.node_areas(filled, geometry, jump_edges(surface))
        lean, metric = lean[self.valid], metric[self.valid]
        return self.grid.z[self.valid], metric / lean, float(np.sum(metric * lean))

    def decoded(self, step):
        """(integer bands as coded, the decoder's wavelet-only reconstruction) for one detail step."""
        quantised = lambda index, band_step: w2.quantise_band(  # noqa: E731
            self.magnitudes[index], self.signs[index], band_step, DEADZONE)
        written = header_steps(step, self.levels)
        qflat = [quantised(0, written[0])]
        steps = band_steps(self.geometry, written, [b.shape for b in self.bands], qflat[0], self.slope_limit)
        qflat += [quantised(index, steps[index]) for index in range(1, len(self.bands))]
        if RDO_LAMBDA and self.levels:   # detail bands to lower
            lowered_toward_zero(qflat, self.magnitudes, steps, self.relevant, expand_steps(written, len(qflat)))
        z = self.transform.inverse(w2.dequantise(qflat, steps), self.grid.shape, self.wavelet, self.levels,
                                   self.geometry.periodic)
        return qflat, z

    def encode(self, step, max_error=None, decoded=None, rounded=None, band_models=None):
        """(file bytes, the heights a decoder gets from them) for one detail step; with ``max_error``
        a correction layer bounds every valid node. ``decoded``: what ``decoded(step)`` gives, when
        the caller has it already (it is changed). ``rounded``: the integer bound of a grid of
        integer samples coded at ``max_error`` (rounding_bounds), whose decoded values are rounded.
        ``band_models``: None to choose the smaller, or the layout to take (``payload``)."""
        qflat, decoded = self.decoded(step) if decoded is None else decoded
        version = written_version(self.grid, rounded is not None, self.compact)
        correction, k = 0.0, None
        if max_error is not None:
            correction = w2.correction_step(max_error)
            k = np.zeros(self.valid.shape, dtype=np.int64)
            k[self.valid] = w2.corrections(self.grid.z, decoded, self.valid, correction)
            decoded[self.valid] += correction * k[self.valid]   # as the decoder adds them
        if rounded is not None:
            decoded[self.valid] = rounded_values(decoded[self.valid], self.grid.raster.sample)   # as the decoder
            max_error = rounded
        decoded[~self.valid] = np.nan
        payload, band_models = self.payload(version, qflat, step, k, band_models)
        lines = self.header_lines(BAND_MODELS_VERSION if band_models else version, step, correction, max_error,
                                  rounded is not None, band_models)
        if version[0] >= COMPACT_VERSION[0]:
            colour = self.colour and self.colour[1]
            return compact.file_bytes(lines[1:-1], payload, colour, version[0]), decoded
        return file_bytes(lines, payload), decoded

    def payload(self, version, qflat, step, k=None, band_models=None):
        """(payload, band_models) of ``version`` (9.0: the list of its sections' bodies) of the integer bands
        ``qflat`` at the detail step ``step``, the corrections ``k`` (a grid, or None) and the grid's charts.
        In 10.x with wavelet levels the detail magnitudes are added with each band's own models: kept so
        (10.1's ``band_models``) where the estimate from their class counts (prefers_band_models) says they
        may pay and the payload is then smaller than with the shared models (its one-byte tables are the
        shared models' worst case), else coded with the shared ones (10.0's), never a byte more than 10.0.
        ``band_models`` True or False takes that layout whatever it costs (the spec's example, fixtures)."""
        per_band = version == TIGHT_VERSION and self.levels > 0
        encoders = self.encoders(version, per_band)
        encoder = encoders[0]
        if version >= FLIPS_VERSION:   # the mask's bits go through the rANS coder before everything else
            encoder.leading = functools.partial(flips.push, decided=flips.decisions(self.valid))
        else:
            encode_mask(encoder, self.valid)
        encode_bands(encoders, qflat, self.relevant, expand_steps(header_steps(step, self.levels), len(qflat)),
                     per_band)
        if k is not None:
            encode_corrections(encoders[-1], k, self.valid)   # with the finest level: 9.0's last section
        if self.grid.charts is not None:
            encode_charts(encoder, self.grid.charts)
        if version == PROGRESSIVE_VERSION:
            return section_payloads(encoders), False
        if not per_band:
            return encoder.finish(), False
        shared = encoder.relabelled(shared_detail_models)
        if band_models is None and self.prefers_band_models(
                encoder.class_counts(detail_model(CONTEXTS, 3 * self.levels, True))):
            own, other = encoder.finish(), shared.finish()
            return (own, True) if len(own) < len(other) else (other, False)
        return (encoder.finish(), True) if band_models else (shared.finish(), False)

    def prefers_band_models(self, counts):
        """True when the class ``counts`` (a row per model id) of the detail magnitudes, added with each band's
        own models, cost fewer bits so than summed onto the shared models: each model's symbols under its
        best one-byte table (10.0's usual record), and a byte for each record the band models add (every
        model id up to the last one used, unused ones included, and two where a band's class count
        changes). ``payload`` makes both payloads only where this says band models may pay: making them for
        every grid took half of a face's encode again."""
        from mzc.codecs.dwt2d.entropy import short_table_bits

        own = [counts[detail_model(0, band, True):detail_model(CONTEXTS, band, True)]
               for band in range(1, 3 * self.levels + 1)]
        bits, sizes = zip(*(short_table_bits(rows) for rows in own))
        used = np.flatnonzero(counts.any(axis=1))   # band 0's model at least
        added = used[-1] - used[used < detail_model(0, 2, True)][-1] + 2 * sum(
            a != b for a, b in zip(sizes, sizes[1:]))
        return sum(bits) + 8 * added < short_table_bits(sum(own))[0]

    def encoders(self, version, band_models=False):
        """The entropy encoder of each level of bands (band_level): 9.0's one per section, its own
        tables and rANS words; before, one encoder for them all (the same object 1 + levels times)."""
        from mzc.codecs.dwt2d.entropy import Encoder

        count = 1 + self.levels if version == PROGRESSIVE_VERSION else 1
        groups = same_size(3 * self.levels, band_models)
        encoders = [Encoder(same_size=groups, parametric=self.compact, short=version >= TIGHT_VERSION)
                    for _ in range(count)]
        return encoders * (1 + self.levels) if count == 1 else encoders

    def header_lines(self, version, step, correction, max_error, rounded=False, band_models=False):
        """The lines of the text header of ``version``, the magic line to the ``data`` line (7.0 codes
        the lines between them as binary fields)."""
        # lines at their defaults are left out: a face's file can be 1.5 KB, and they were 50 B of it
        lines = [magic_line(KIND, version), *grid_header_lines(self.grid, write_defaults=False, chart_records=False,
                                                               counted=version[0] >= FLIPS_VERSION[0])]
        if self.grid.charts is not None:   # their records are in the payload: 8-10 bytes a chart, not 25
            lines.append(f"chart_count {len(self.grid.charts)}")
        if self.wavelet != DEFAULT_WAVELET:
            lines.append(f"wavelet {self.wavelet}")
        if self.levels != w2.default_levels(self.grid.shape, self.transform.coarsest):
            lines.append(f"levels {self.levels}")
        lines.append("steps " + " ".join(map(format_number, header_steps(step, self.levels))))
        if self.slope_limit != SLOPE_LIMIT:
            lines.append(f"slope_limit {format_number(self.slope_limit)}")
        if correction > 0:
            lines.append(f"correction {format_number(correction)}")
        if rounded:
            lines.append(f"rounding {ROUNDING}")
        if max_error is not None:
            lines.append(f"max_error {format_number(max_error)}")
        if band_models:
            lines.append("band_models 1")
        if self.colour is not None:
            lines.append(self.colour[0])
        return [*lines, "data"]

    def surface_rms(self, decoded):
        """RMS surface error of a wavelet-only reconstruction (``decoded`` of a step), estimated
        at the valid nodes: the value error times cos(t) (the distance along the normal, t the
        lean of the surface from the node's line), weighted by the surface area of each node,
        a/cos(t) (a = 1 on planar grids, the projection's metric area on central ones)."""
        heights, weight, area = self.surface_terms
        if not heights.size:
            return 0.0
        error = decoded[1][self.valid]
        error -= heights   # in place, the same numbers: ((z' - z)^2 w) summed
        np.square(error, out=error)
        error *= weight
        return float(np.sqrt(np.sum(error) / area))

    def finest_step(self):
        """The smallest detail step the searches try: FINEST_MARGIN times the one that would
        quantise the largest coefficient to MAX_QUANTUM (the margin covers band 0's smaller step,
        the coarser levels' and the slope factors), or 0 for a grid of zeros."""
        largest = max(float(m.max(initial=0.0)) for m in self.magnitudes)
        return FINEST_MARGIN * largest / w2.MAX_QUANTUM

    def height_range(self):
        """Spread of the valid heights (at least 1e-6): scales the step searches."""
        z = self.grid.z[self.valid]
        return max(float(z.max() - z.min()), 1e-6) if z.size else 1.0


def section_payloads(encoders):
    """The bodies of 9.0's base and level sections from their encoders, in order. The base section's
    tables are chosen by the whole file's class counts, as 8.0's one payload's are, so that each level
    section can keep them all (a table count of 0) or some (entropy.KEPT) where that costs less than
    tables of its own, each section choosing for itself."""
    counts = [encoder.class_counts() for encoder in encoders]
    rows = max(len(c) for c in counts)
    payloads = [encoders[0].finish(sum(np.pad(c, ((0, rows - len(c)), (0, 0))) for c in counts))]
    for encoder in encoders[1:]:
        encoder.prior = encoders[0].tables
        payloads.append(encoder.finish())
    return payloads


def written_version(grid, rounded, compact=True):
    """The version the reference encoder writes a grid coded whole in: 10.0 (``compact`` True), or the
    container version ``compact`` names (9.0 for ``progressive``, 7.0 and 8.0 for their tests), or without
    ``compact`` (a tile of a 5.0 file) the 3.x, 4.0 or 6.0 (``rounded``: decoded values rounded to
    integers) it was before."""
    if compact:
        return TIGHT_VERSION if compact is True else tuple(compact)
    if rounded:
        return ROUNDED_VERSION
    return file_version(grid, VERSION, PROJECTED_VERSION, GEOREFERENCED_VERSION, CHARTED_VERSION)


def header_steps(step, levels):
    """The ``steps`` line's values for a detail step: band 0's step, then every detail band's
    (just the one step when band 0 is the grid itself)."""
    return [w2.round_step(APPROXIMATION_GAIN * step), step] if levels else [step]


def expand_steps(steps, count):
    """One step per band from the ``steps`` line: one value for all; two: band 0's, then the
    finest level's detail step, each coarser level's LEVEL_RATIO times the next finer one's
    (repeated binary64 products, so every decoder gets the same numbers); or one each."""
    if len(steps) == 1:
        return list(steps) * count
    if len(steps) == 2:
        per_level = [steps[1]]
        for _ in range((count - 1) // 3 - 1):
            per_level.append(per_level[-1] * LEVEL_RATIO)
        return [steps[0]] + [step for step in reversed(per_level) for _ in range(3)]
    return list(steps)


def band_steps(geometry, steps, shapes, approximation_q, slope_limit):
    """Every band's step (one number, or one per coefficient for the slope-scaled detail
    bands) from the ``steps`` line, the band shapes and the grid's geometry."""
    levels = (len(shapes) - 1) // 3
    return w2.step_maps(expand_steps(steps, len(shapes)), approximation_q, levels, geometry, shapes, slope_limit)


def check_options(options):
    """Refuse more than one of max_error, rmse and size (none: ``default_rmse``), both colour targets,
    and a tile side out of range."""
    if sum(options.get(name) is not None for name in TARGETS) > 1:
        raise MzcError("give one of max_error, rmse or size, not several", field="dwt2d", options=TARGETS)
    if sum(options.get(name) is not None for name in COLOUR_TARGETS) > 1:
        raise MzcError("give one of colour_psnr or colour_max_error, not both", field="dwt2d",
                       options=COLOUR_TARGETS)
    from mzc.codecs.dwt2d.tiles import check_tile_option

    check_tile_option(options.get("tile"))


def default_rmse(grid):
    """The target without one given: an RMS surface error of DEFAULT_RMSE_SPACING times the
    grid's smaller node spacing, well under what sampling the surface at that spacing loses
    (a face's default grid, 0.75 mm: 0.075 mm; a 1 m DEM: 0.1 m). A geographic grid's spacing
    is taken in metres at its centre (1 arc-second at 39.5 N: 23.9 m, so 2.4 m of height)."""
    from mzc.georef import centre_of, is_geographic, metres_per_unit

    if not is_geographic(grid):
        return DEFAULT_RMSE_SPACING * min(grid.d1, grid.d2)
    east, north = metres_per_unit(grid.crs, centre_of(grid)[1])
    return DEFAULT_RMSE_SPACING * min(grid.d2 * east, grid.d1 * north)


def encode_grid(grid, **options):
    """The bytes of a ZGrid (options checked by CODEC): see ``encode_grid_with_decoded``."""
    return encode_grid_with_decoded(grid, **options)[0]


def encode_grid_with_decoded(grid, tile=None, compact=True, progressive=None, **options):
    """(bytes, the heights a decoder gets from them) of a ZGrid (options checked by CODEC): whole
    (``encode_whole``; without ``compact`` in the text-header versions, with ``progressive`` in 9.0)
    or, when ``tile`` or its size says so, in tiles (mzc.codecs.dwt2d.tiles)."""
    from mzc.codecs.dwt2d import tiles

    side = tiles.grid_tile_side(grid, tile)
    check_whole(progressive, side)
    if side is None:
        return encode_whole(grid, compact=PROGRESSIVE_VERSION if progressive else compact, **options)
    data = tiles.encode(tiles.GridSource(grid), side, options)
    return data, tiles.read(data).z


def window_writer(source, options, scheduler=None):
    """The chunks of the file of a grid read window by window (``source``: a Frame and its blocks,
    mzc.rasters.windows) with CODEC's ``options`` (checked), its tiles coded as Dask tasks on the
    ``scheduler`` at that address when given; or None when it is coded whole (read it whole then:
    the same bytes as ever)."""
    from mzc.codecs.dwt2d import tiles

    options = dict(options)
    side = tiles.tile_side(source.frame.shape, options.pop("tile", None))
    check_whole(options.pop("progressive", None), side)
    if side is None:
        return None
    return tiles.file_chunks(source, side, options, getattr(source, "spill_dir", None), scheduler)


def check_whole(progressive, side):
    """Refuse ``progressive`` for a grid coded in tiles of ``side`` (not None): 9.0 codes a grid whole."""
    if progressive and side is not None:
        raise MzcError(f"a progressive file (mzc-dwt2d 9.0) codes the grid whole, and this one is coded in tiles of "
                       f"{side} x {side} nodes: give --tile 0 (or leave out --progressive)", field="progressive")


def encode_whole(grid, max_error=None, rmse=None, size=None, wavelet=DEFAULT_WAVELET, level=None, slope_limit=None,
                 unit_checked=False, compact=True, colour_psnr=None, colour_max_error=None, surface=None):
    """(bytes, the heights a decoder gets from them) of a ZGrid coded whole; at most one of
    ``max_error`` (bound at every valid node, grid units), ``rmse`` (target RMS surface error; on a
    geographic grid the vertical one, in the height unit) or ``size`` (target file bytes, not
    exceeded when reachable), none being ``default_rmse``;
    ``unit_checked`` when the caller has judged the grid's unit already (a tile, by its tiled
    grid's CRS); without ``compact`` the file has a 3.x, 4.0 or 6.0 text header, as
    a tile of a 5.0 file has (written_version). A 7.0 file of a grid with colours carries them in its
    colour section, coded at ``colour_psnr`` dB or within ``colour_max_error`` levels (``colour_section``).
    ``surface``: the grid of the surface whose RMS error ``rmse`` aims at, when ``grid`` is a residual
    of it (mzc.prior: the mean added back at decode), its mask and shape ``grid``'s, its node lines
    (projection, frame, spacings) its own.

    ``slope_limit`` defaults to SLOPE_LIMIT for ``rmse`` and ``size``, whose errors are
    surface distances, and to 1 (equal steps) for ``max_error``, a bound on heights, where
    slope-scaled steps measured 3% larger files (f18, E = 0.1), and for a geographic grid,
    whose lean has no meaning in degrees (``check_slope_limit``).
    """
    if max_error is None and rmse is None and size is None:
        rmse = default_rmse(grid)
    name, target = next((n, v) for n, v in (("max_error", max_error), ("rmse", rmse), ("size", size)) if v is not None)
    if max_error is None and not unit_checked:
        check_shared_unit(grid, name)
    if slope_limit is None:
        slope_limit = 1.0 if max_error is not None or is_geographic(grid) else SLOPE_LIMIT
    check_slope_limit(grid, slope_limit)
    colour = colour_section(grid, colour_psnr, colour_max_error) if compact else None
    prepared = Prepared(grid, wavelet, level, slope_limit, compact, colour, surface)
    if max_error is not None:
        bound, rounded = rounding_bounds(grid, max_error) or (max_error, None)
        # the smallest file, except that a finer step (lower RMS error) wins within ALPHA_SLACK of it
        files = [prepared.encode(w2.round_step(a * bound), bound, rounded=rounded) for a in ALPHAS]
        smallest = min(len(data) for data, _ in files)
        return next(file for file in files if len(file[0]) <= smallest * (1 + ALPHA_SLACK))
    span = prepared.height_range()
    finest = max(1e-9 * span, prepared.finest_step())
    if rmse is not None:
        cost, kept = keeping_best(prepared.decoded, prepared.surface_rms, target)
        step = w2.search_step(cost, target, finest, 4.0 * span, RMS_GUESS * target, RMS_SLOPE, snap=w2.round_step)
        return prepared.encode(step, decoded=kept.get(step))
    # size falls as the step grows, so search the largest 1/step whose file still fits
    cost, kept = keeping_best(lambda inv: prepared.encode(w2.round_step(1.0 / inv)), lambda file: len(file[0]), target)
    inverse = w2.search_step(cost, target, 1.0 / (4.0 * span), 1.0 / finest, SIZE_GUESS / span, SIZE_SLOPE,
                             snap=lambda inv: 1.0 / w2.round_step(1.0 / inv))
    return kept.get(inverse) or prepared.encode(w2.round_step(1.0 / inverse))


def colour_section(grid, psnr=None, max_error=None):
    """(the header line of its target, the colour section's bytes) of a grid's colours, None without
    them: coded within ``max_error`` levels, else at ``psnr`` dB (default DEFAULT_COLOUR_PSNR) over the
    valid nodes (mzc.codecs.dwt2d.colour, spec/colour.md); colours finer than the nodes
    (``ZGrid.fine_colors``) are coded whole, with their scale."""
    if grid.colors is None:
        return None
    from mzc.codecs.dwt2d.colour import encode_colour

    image = grid.colors if grid.fine_colors is None else grid.fine_colors
    coded = functools.partial(encode_colour, image, grid.valid, scale=grid.colour_scale, charts=grid.charts)
    if max_error is not None:
        return f"colour_max_error {int(max_error)}", coded(max_error=max_error)
    psnr = DEFAULT_COLOUR_PSNR if psnr is None else psnr
    return f"colour_psnr {format_number(psnr)}", coded(psnr=psnr)


def keeps_colour(grid, options):
    """The colour scale of ``grid`` that its file with ``options`` carries: coded whole, its own (a
    colour section of any scale); in tiles, 1 (the nodes' colours, a section a tile of 11.0), but 0
    for a raster's integers in rounded tiles (6.0 files, which code the shape alone)."""
    from mzc.codecs.dwt2d import tiles

    if tiles.grid_tile_side(grid, options.get("tile")) is None:
        return grid.colour_scale
    return 0 if tiles.rounds(tiles.GridSource(grid), options) else 1


def rounding_bounds(grid, max_error):
    """(the bound to code at, the bound kept) for a grid of a raster's integer samples (its raster's
    sample type is an integer type that holds every valid value), else None. Its decoded values
    are rounded to integers (``rounding integer``, spec/dwt2d.md, Rounding), so a value coded
    within floor(E) + 1/2 of its integer comes back within floor(E) <= E of it, exactly an
    integer: the int16 DEM decodes to int16 samples, and E = 1 codes at 1.5, below 1 losslessly."""
    if grid.raster is None or np.dtype(grid.raster.sample).kind not in "iu":
        return None
    from mzc.rasters import holds

    values = grid.z[grid.valid]
    if not holds(grid.raster.sample, values):
        return None
    kept = float(np.floor(max_error))
    largest = float(np.abs(values).max(initial=0.0)) + kept + 1.0
    return kept + 0.5 - ROUNDING_ULPS * float(np.spacing(largest)), kept


def read_rounding(header, fields, since):
    """True when a header of version ``since`` or later (6.0 and 7.0 files, 5.1 tiled ones) has the
    ``rounding`` line (checked: its one value, and a ``raster`` line of an integer type among the grid
    ``fields``); before, the line is ignored (spec/dwt2d.md, Rounding; Tiled files)."""
    if (header.major, header.minor) < since or not header.has("rounding"):
        return False
    header.word("rounding", (ROUNDING,))
    if fields.get("raster") is None or np.dtype(fields["raster"].sample).kind not in "iu":
        raise header.error("rounding", "rounds a raster of integer samples: the raster line names none")
    return True


def rounded_values(values, sample):
    """``values`` rounded to the nearest integer (ties to even) and held to the range of the
    integer type ``sample``, as a 6.0 decoder gives them (spec/dwt2d.md, Rounding): the input's
    integers lie in that range, so neither step takes a value farther from its own."""
    info = np.iinfo(sample)
    return np.clip(np.rint(values), info.min, info.max)


def keeping_best(work, measure, target):
    """(cost, kept) for a search of the largest x whose cost meets ``target``: cost(x) is
    measure(work(x)), and ``kept`` holds {x: work(x)} of the largest x so far whose cost met
    it: what the search returns, whose work is then not done again."""
    kept = {}

    def cost(x):
        result = work(x)
        value = measure(result)
        if value <= target and all(x > best for best in kept):
            kept.clear()
            kept[x] = result
        return value

    return cost, kept


def check_shared_unit(grid, field):
    """Refuse ``rmse`` and ``size`` on a planar grid whose x, y and z cannot share a unit.

    Both measure errors as distances across all three axes (the slope model weighs a
    height error by the lean of the surface); a DEM in lon/lat degrees with heights in
    metres leans by nearly 90 degrees everywhere to that model, and a --rmse of 1.34 once
    gave 306 m. Such grids show heights spanning more than UNIT_RATIO times their width,
    or GEOGRAPHIC_RATIO times on a grid within lon/lat bounds with spacings under
    GEOGRAPHIC_STEP (a DEM's arc-seconds). Central grids are lengths by
    construction. A grid with a CRS is judged by its CRS instead: a projected one shares its
    unit, and a geographic one is measured by its heights alone (``Prepared.surface_terms``)."""
    if grid.crs is not None:
        return
    z = grid.z[grid.valid]
    if grid.projection != "planar" or z.size < 2:
        return
    xs, ys = grid.xs(), grid.ys()
    width = max(np.ptp(xs), np.ptp(ys), grid.d1, grid.d2)
    ratio = float(np.ptp(z)) / width
    geographic = np.abs(xs).max() <= 180 and np.abs(ys).max() <= 90 and max(grid.d1, grid.d2) < GEOGRAPHIC_STEP
    if ratio > UNIT_RATIO or (geographic and ratio > GEOGRAPHIC_RATIO):
        raise MzcError(f"the heights span {ratio:.3g} times the grid's width, so x, y and z cannot share one unit "
                       f"(lon/lat degrees with heights in metres?) and a surface error means nothing: project "
                       f"the grid to a metric frame, or use --max-error, which bounds the heights alone",
                       field=field)


def check_slope_limit(grid, slope_limit):
    """Refuse slope-scaled steps (``slope_limit`` above 1) on a geographic grid: the lean they
    scale by would be measured across degrees and metres (its decoder reads no metric)."""
    if slope_limit > 1 and is_geographic(grid):
        raise MzcError("a geographic grid's lean is not measured across degrees and metres: its steps are "
                       "equal (slope_limit 1)", field="slope_limit")


# --------------------------------------------------------------------------- decoder


def read_codec_fields(header, shape, transform):
    """(wavelet, levels, steps of every band, slope limit, correction step) from the header, each checked."""
    wavelet = header.word("wavelet", transform.wavelets, required=False, default=DEFAULT_WAVELET)
    levels = header.integer("levels", 0, w2.MAX_LEVELS, required=False,
                            default=w2.default_levels(shape, transform.coarsest))
    steps = header.floats("steps", None)
    if len(steps) not in {1, 1 + 3 * levels} | ({2} if levels else set()):
        allowed = f"1, 2 or {1 + 3 * levels}" if levels else "1"
        raise header.error("steps", f"expected {allowed} values, found {len(steps)}")
    if min(steps) <= 0:
        raise header.error("steps", "every step must be > 0")
    slope_limit = header.floats("slope_limit", 1, required=False, default=[SLOPE_LIMIT])[0]
    if slope_limit < 1:
        raise header.error("slope_limit", "must be >= 1")
    correction = header.floats("correction", 1, required=False, default=[0.0])[0]
    if correction < 0:
        raise header.error("correction", "must be >= 0")
    header.word("coder", (CODER,), required=header.major == 2)
    return wavelet, levels, expand_steps(steps, 1 + 3 * levels), slope_limit, correction


def read(data, source="<bytes>", wanted=None):
    """Decode dwt2d bytes (9.0, 8.0, 7.0, 3.x, 4.0, 6.0, 2.0 with its periodised transform, or the tiles of
    5.0) into a ZGrid; any bad input raises MzcError. ``wanted`` K (a 9.0 file's alone) decodes band 0
    and the K coarsest detail levels, the finer bands zero (all of them from K = the file's levels on);
    a 9.0 file cut short decodes to its whole levels, with a warning (``warn_cut``)."""
    from mzc.codecs.dwt2d import tiles

    progressive = compact.major(data) == PROGRESSIVE_VERSION[0]
    if wanted is not None and not progressive:
        raise MzcError("decoding some levels takes a progressive file (mzc-dwt2d 9.0, written by encode "
                       "--progressive), and this is not one: decode it whole", source=source, field="levels")
    if tiles.is_tiled(data):
        return tiles.read(data, source)
    parametric = compact.is_compact(data)   # 7.0's table records
    colour = None
    if parametric:
        header, payload, colour = compact.read(data, source)
        bodies = payload if progressive else [payload]
    else:
        header, body, _first = read_header(data, source, KIND, PROGRESSIVE_VERSION[0], oldest_major=OLDEST_MAJOR,
                                           projected_major=PROJECTED_VERSION[0], checksum_since=CHECKSUM_SINCE,
                                           binary=True, georef_since=GEOREF_SINCE, charted_major=CHARTED_VERSION[0])
        bodies = [body]
    fields, rows, cols = read_grid_fields(header)
    transform = w2.TRANSFORMS[header.major]
    wavelet, levels, steps, slope_limit, correction = read_codec_fields(header, (rows, cols), transform)
    rounding = read_rounding(header, fields, ROUNDED_VERSION)
    geometry = w2.Geometry.of(fields["d1"], fields["d2"], fields["origin"], (rows, cols),
                              fields.get("projection", "planar"), fields.get("radius"))
    band_models = header.integer("band_models", 1, 1, required=False, default=0) == 1
    decoders = section_decoders(bodies, levels, wanted, source, parametric, progressive,
                                short=header.major >= TIGHT_VERSION[0], groups=same_size(3 * levels, band_models))
    valid = (flips.decode if header.major >= FLIPS_VERSION[0] else decode_mask)(decoders[0], rows, cols)
    relevant = w2.flatten(transform.relevance(valid, wavelet, levels, geometry.periodic))
    qflat = decode_bands(decoders, relevant, steps, band_models)
    whole = len(decoders) == 1 + levels   # every level decoded: the corrections are the last section's
    with np.errstate(over="ignore", invalid="ignore"):
        bands = w2.dequantise(qflat, band_steps(geometry, steps, [q.shape for q in qflat], qflat[0], slope_limit))
        del qflat   # gone before the inverse: f18's decode peaks 4 MB lower, 20% fewer fresh pages faulted in
        z = transform.inverse(bands, (rows, cols), wavelet, levels, geometry.periodic)
        if correction > 0 and whole:
            k = decoders[-1].read_rows(valid, np.zeros(valid.shape), CORRECTION_THRESHOLDS, correction_model(0))
            z[valid] += correction * k[valid]
        if rounding:
            z[valid] = rounded_values(z[valid], fields["raster"].sample)
    if header.charted and header.has("chart_count"):
        fields["charts"] = decode_charts(decoders[0], header.integer("chart_count", 1, MAX_CHARTS))
    for decoder in {id(d): d for d in decoders}.values():
        decoder.check_end()
    if not np.isfinite(z[valid]).all():
        raise MzcError("decoded heights are not finite (corrupt steps or payload)", source=source, field="data")
    z[~valid] = np.nan
    if colour is not None:
        from mzc.codecs.dwt2d.colour import decode_colour

        fields["fine_colors"] = decode_colour(colour, valid, source, fields.get("charts"))   # its scale may be 1
    grid = ZGrid(z=z, **fields)
    coloured = header.has("colour_psnr") or header.has("colour_max_error")
    if progressive and (len(bodies) - 1 < levels or coloured and colour is None):   # cut short: said once decoded
        warn_cut(source, len(bodies) - 1, levels, coloured)
    return grid


def section_decoders(bodies, levels, wanted, source, parametric, progressive, short=False, groups=SAME_SIZE):
    """The entropy decoder of each level of bands (band_level) that is decoded: outside 9.0, the one
    payload's (``bodies``' one; ``parametric``: 7.0's table records, ``short``: 10.0's, ``groups``: its
    models of one class count each, same_size) for every level; in 9.0 (``progressive``), the base
    section's and each level section's that the file holds, up to ``wanted`` (None: all of them)."""
    from mzc.codecs.dwt2d.entropy import Decoder

    if not progressive:
        return [Decoder(bodies[0], source, groups, parametric, short=short)] * (1 + levels)
    if len(bodies) > 1 + levels:
        raise MzcError(f"{len(bodies) - 1} level sections for {levels} wavelet levels", source=source, field="data")
    base = Decoder(bodies[0], source, SAME_SIZE, True)
    kept = bodies[1:1 + (levels if wanted is None else min(wanted, levels))]
    return [base, *(Decoder(body, source, SAME_SIZE, True, base.tables) for body in kept)]


def warn_cut(source, complete, levels, coloured):
    """Say in one line that a 9.0 file was cut short: how many of its detail levels it holds whole
    (and so decodes), and what else is lost with the rest: the colours, the max_error corrections."""
    import warnings

    from mzc.errors import MzcWarning

    if complete < levels:
        message = (f"the file is cut short: decoded {complete} of its {levels} detail levels, a coarser surface "
                   f"(without its finest levels{' and colours' if coloured else ''})")
    else:
        message = "the file is cut short in its colour section: the surface is whole, its colours are left out"
    warnings.warn(MzcWarning(f"{source}: {message}"), stacklevel=3)


CODEC = Codec(
    "dwt2d", encode_grid, read, writer_with_decoded=encode_grid_with_decoded, version=COLOURED_TILED_VERSION,
    oldest_major=OLDEST_MAJOR, extension=".mzw2", spec="spec/dwt2d.md", window_writer=window_writer,
    summary="2D wavelet of the whole grid, entropy coded, error-bounded", check_options=check_options,
    example={"max_error": 0.05}, keeps_colour=keeps_colour, options=(
        Option("max_error", float, None, 0, MAX_MAGNITUDE, min_open=True, metavar="E",
               help="|decoded - input| <= E at every valid node (a raster of integers: integers within "
                    "floor(E))."),
        Option("rmse", float, None, 0, MAX_MAGNITUDE, min_open=True, metavar="E",
               help="Aim at this RMS surface error (value error times cos of the lean) [default without "
                    "--max-error or --size: a tenth of the node spacing]."),
        Option("size", int, None, 1, metavar="BYTES", help="Aim at this file size."),
        Option("wavelet", w2.TRANSFORMS[VERSION[0]].wavelets, DEFAULT_WAVELET,
               help="Wavelet: bior4.4 (CDF 9/7) or bior2.2 (LeGall 5/3)."),
        Option("level", int, None, 0, w2.MAX_LEVELS, metavar="N",
               help="Wavelet levels (--dwt2d: from the grid size unless given)."),
        Option("slope_limit", float, None, 1, metavar="F",
               help="Steps grow as 1/sqrt(cos lean) up to F times; 1 = equal steps [default: 2 for rmse and size, "
                    "1 for max_error]."),
        Option("colour_psnr", float, None, 0, 200, min_open=True, metavar="DB",
               help="Code the grid's colours at this PSNR over the valid nodes [default: 36]."),
        Option("colour_max_error", int, None, 0, 127, metavar="LEVELS",
               help="Code the grid's colours within this many 8-bit levels at every valid node (0: lossless)."),
        Option("progressive", bool, None,
               help="Write mzc-dwt2d 9.0: the levels in sections, coarsest first, each with its own checksum, "
                    "so that a cut file (or decode --levels K) decodes to a coarser surface; about 120 bytes "
                    "more than the default (10.0) on a face. Grids coded whole only."),
        Option("tile", int, None, 0, metavar="N",
               help="Code the grid in independent N x N tiles (4..4096), each decoded on its own; 0 = whole "
                    "[default: tiles of 1024 above 1024 x 1024 nodes]."),
    ))
write = CODEC.encode
