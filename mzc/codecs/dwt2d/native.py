"""The compiled loops of the dwt2d payload decoder (entropy.Decoder calls them).

A detail band's contexts depend on the rows above and, in odd columns, on the even columns
just decoded, so its rows cannot be decoded as one vector: a Python loop over rows made 92%
of a face's decode (about 2,000 coder calls). Here the whole row loop of a band runs in
numba-compiled code: the rANS arithmetic of spec/dwt2d.md (section 'Payload': constriction's
AnsCoder with 32-bit words, a 64-bit state and 24-bit probabilities, written out so the
decoder needs no constriction), the raw bits, the contexts in the same binary64 operations
as the encoder's numpy (``neighbours``, ``beside``, ``np.digitize``), the stable order by
context, and the signs. The mask's spans are filled by one such loop too.

Compiled code raises no MzcError: each kernel checks what it reads and returns an error
code, with a detail such as the missing model id in ``cursor[DETAIL]``, which
``Decoder.check`` turns into the one-line message. Indices come from checked model ids,
tables whose cumulative rows end at 2**14 and raw-bit counts checked before reading.
The kernels compile on first use and are cached on disk (next to this file, or in numba's
user cache directory where that is not writable), so later processes load them instead.
"""

import numpy as np
from numba import njit

from mzc.codecs.dwt2d.entropy import ANS_PRECISION, TABLE_BITS

SCALE = ANS_PRECISION - TABLE_BITS      # F = f * 2**SCALE: the 14-bit tables as 24-bit probabilities
WORD_BITS = 32
# kernel results (0 = fine), and the slots of the int64 ``cursor`` the kernels update
OK, NO_TABLE, RAW_BITS_END, NOT_A_SIGN = range(4)
WORDS_LEFT, BIT_POSITION, DETAIL = range(3)


def compiled(function):
    """numba's ``njit`` with the on-disk cache; without it where no cache directory is writable
    (numba refuses ``cache=True`` there: the decoder then compiles in each process instead of failing)."""
    try:
        return njit(cache=True)(function)
    except RuntimeError:
        return njit(function)


@compiled
def decode_classes(state, cursor, words, cumulative, models, count, out):
    """``count`` classes into ``out``, class i with table ``models[i]`` (ids checked by the caller).

    rANS as spec/dwt2d.md states it: m = x mod 2**24, the class s whose cumulative range
    holds m, x = F(s) (x >> 24) + m - B(s), then a refill from the words left when x < 2**32.
    ``cumulative`` has a row of 14-bit cumulative frequencies per table, 2**14 past its last class.
    """
    x = state[0]
    left = cursor[WORDS_LEFT]
    low_mask = np.uint64((1 << ANS_PRECISION) - 1)
    refill_below = np.uint64(1) << np.uint64(WORD_BITS)
    for i in range(count):
        row = cumulative[models[i]]
        m = x & low_mask
        quantile = np.int64(m >> np.uint64(SCALE))
        s = 0
        while row[s + 1] <= quantile:
            s += 1
        start = np.uint64(row[s]) << np.uint64(SCALE)
        frequency = np.uint64(row[s + 1] - row[s]) << np.uint64(SCALE)
        x = frequency * (x >> np.uint64(ANS_PRECISION)) + (m - start)
        if x < refill_below and left > 0:
            left -= 1
            x = (x << np.uint64(WORD_BITS)) | np.uint64(words[left])
        out[i] = s
    state[0] = x
    cursor[WORDS_LEFT] = left


@compiled
def take_raw_bits(cursor, bits, classes, count, signed, out):
    """The values of ``count`` classes from the raw bits (sign bit first where ``signed``, then
    the bits below the leading one); RAW_BITS_END, reading nothing, when the bits run out."""
    need = 0
    for i in range(count):
        if classes[i] > 0:
            need += classes[i] - 1 + signed
    position = cursor[BIT_POSITION]
    if position + need > len(bits):
        return RAW_BITS_END
    for i in range(count):
        k = classes[i]
        if k == 0:
            out[i] = 0
            continue
        negative = False
        if signed:
            negative = bits[position] == 1
            position += 1
        value = np.int64(1)
        for _ in range(k - 1):
            value = (value << 1) | np.int64(bits[position])
            position += 1
        out[i] = -value if negative else value
    cursor[BIT_POSITION] = position
    return OK


@compiled
def read_values(state, cursor, words, bits, cumulative, model, count, signed, out):
    """``count`` values of one model into ``out`` (the model id checked by the caller)."""
    models = np.empty(count, dtype=np.int64)
    for i in range(count):
        models[i] = model
    classes = np.empty(count, dtype=np.int64)
    decode_classes(state, cursor, words, cumulative, models, count, classes)
    return take_raw_bits(cursor, bits, classes, count, signed, out)


@compiled
def context_of(value, thresholds):
    """``np.digitize(value, thresholds)`` of increasing thresholds: how many are <= value
    (all of them for NaN, which numpy sorts last)."""
    k = 0
    while k < len(thresholds) and not value < thresholds[k]:
        k += 1
    return k


@compiled
def sign_of(value):
    """-1, 0 or +1, as np.sign."""
    return 1 if value > 0 else (-1 if value < 0 else 0)


@compiled
def decode_rows(state, cursor, words, bits, cumulative, where, active, thresholds, first_model,
                parent, weights, first_sign_model, sign_contexts, out):
    """Inverse of the row-by-row context coding (encode_bands, encode_corrections) into ``out``
    (zeros outside ``where``); OK or an error code.

    Each row comes in two passes, its even columns then its odd ones; a pass decodes its
    values by context (model ``first_model`` + context), left to right within one. The
    context counts the ``thresholds`` <= a, with a = active + n (+ b in odd columns) in the
    binary64 operations of ``neighbours`` and ``beside``. With ``first_sign_model`` >= 0
    (detail bands) the values are magnitudes, followed per pass by the sign symbols of its
    nonzero ones, predicted from the sign above, ``parent`` and the signs beside with
    ``weights`` (sign_prediction); otherwise each value carries its sign in the raw bits.
    """
    rows, cols = where.shape
    tables = cumulative.shape[0]
    signs = first_sign_model >= 0
    cells = np.empty(cols, dtype=np.int64)
    context = np.empty(cols, dtype=np.int64)
    starts = np.empty(len(thresholds) + 2, dtype=np.int64)
    ordered = np.empty(cols, dtype=np.int64)
    models = np.empty(cols, dtype=np.int64)
    classes = np.empty(cols, dtype=np.int64)
    values = np.empty(cols, dtype=np.int64)
    predicted = np.empty(cols, dtype=np.int64)
    near = np.empty(cols, dtype=np.float64)
    for r in range(rows):
        for c in range(cols):   # active + neighbours(row above, row two above), as numpy adds them
            n = np.float64(abs(out[r - 1, c])) if r >= 1 else 0.0
            if c >= 1:
                n = n + 0.5 * (np.float64(abs(out[r - 1, c - 1])) if r >= 1 else 0.0)
            if c + 1 < cols:
                n = n + 0.5 * (np.float64(abs(out[r - 1, c + 1])) if r >= 1 else 0.0)
            n = n + 0.5 * (np.float64(abs(out[r - 2, c])) if r >= 2 else 0.0)
            near[c] = active[r, c] + n
        for odd in range(2):
            count = 0
            top = 0
            for c in range(odd, cols, 2):
                if not where[r, c]:
                    continue
                a = near[c]
                if odd:   # beside: the even columns left and right, just decoded
                    b = np.float64(abs(out[r, c - 1]))
                    if c + 1 < cols:
                        b = b + np.float64(abs(out[r, c + 1]))
                    a = a + b
                k = context_of(a, thresholds)
                cells[count] = c
                context[count] = k
                top = max(top, k)
                count += 1
            if count == 0:
                continue
            if first_model + top >= tables:
                cursor[DETAIL] = first_model + top
                return NO_TABLE
            # stable counting sort by context: left to right within one, as np.argsort(kind="stable")
            for k in range(len(starts)):
                starts[k] = 0
            for i in range(count):
                starts[context[i] + 1] += 1
            for k in range(1, len(starts)):
                starts[k] += starts[k - 1]
            for i in range(count):
                ordered[starts[context[i]]] = cells[i]
                models[starts[context[i]]] = first_model + context[i]
                starts[context[i]] += 1
            decode_classes(state, cursor, words, cumulative, models, count, classes)
            code = take_raw_bits(cursor, bits, classes, count, 0 if signs else 1, values)
            if code != OK:
                return code
            for i in range(count):
                out[r, ordered[i]] = values[i]
            if not signs:
                continue
            nonzero = 0
            top = 0
            for i in range(count):   # the pass's nonzero values, left to right
                c = cells[i]
                if out[r, c] == 0:
                    continue
                side = 0
                if odd:
                    side = sign_of(out[r, c - 1]) + (sign_of(out[r, c + 1]) if c + 1 < cols else 0)
                above = sign_of(out[r - 1, c]) if r >= 1 else 0
                score = weights[0] * above + weights[1] * sign_of(parent[r, c]) + weights[2] * side
                k = min(abs(score), sign_contexts - 1) + sign_contexts * odd
                ordered[nonzero] = c
                models[nonzero] = first_sign_model + k
                predicted[nonzero] = 1 if score >= 0 else -1
                top = max(top, first_sign_model + k)
                nonzero += 1
            if nonzero == 0:
                continue
            if top >= tables:
                cursor[DETAIL] = top
                return NO_TABLE
            decode_classes(state, cursor, words, cumulative, models, nonzero, classes)
            code = take_raw_bits(cursor, bits, classes, nonzero, 0, values)
            if code != OK:
                return code
            for i in range(nonzero):
                if values[i] > 1:
                    return NOT_A_SIGN
            for i in range(nonzero):
                c = ordered[i]
                out[r, c] = out[r, c] * predicted[i] * (1 - 2 * values[i])
    return OK


@compiled
def fill_spans(lengths, unchanged, same, new, valid):
    """The validity mask into ``valid`` (rows x cols, all False) from each row's flips: the row
    above's moved by ``same`` where the row's flip count is ``unchanged``, else the gaps of
    ``new``; -1, or the first row whose flips leave 0..cols or do not increase."""
    rows, cols = valid.shape
    previous = np.zeros(cols + 2, dtype=np.int64)
    flips = np.zeros(cols + 2, dtype=np.int64)
    used_same = used_new = 0
    for r in range(rows):
        n = lengths[r]
        for i in range(n):
            if unchanged[r]:
                flips[i] = previous[i] + same[used_same + i]
            else:
                flips[i] = (flips[i - 1] if i else -1) + new[used_new + i] + 1
        if unchanged[r]:
            used_same += n
        else:
            used_new += n
        if n and (flips[0] < 0 or flips[n - 1] > cols):
            return r
        for i in range(1, n):
            if flips[i] <= flips[i - 1]:
                return r
        for i in range(0, n, 2):
            for c in range(flips[i], flips[i + 1]):
                valid[r, c] = True
        for i in range(n):
            previous[i] = flips[i]
    return -1
