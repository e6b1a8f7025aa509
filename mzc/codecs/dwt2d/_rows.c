/* The compiled loops of the dwt2d payload decoder (mzc.codecs.dwt2d.entropy.Decoder calls them).

A detail band's contexts depend on the rows above and, in odd columns, on the even columns just
decoded, so its rows cannot be decoded as one numpy vector: a Python loop over rows made 92% of a
face's decode. Here the whole row loop of a band runs in C: the rANS arithmetic of spec/dwt2d.md
(section 'Payload': constriction's AnsCoder with 32-bit words, a 64-bit state and 24-bit
probabilities), the raw bits, the contexts in the same binary64 operations as the encoder's numpy
(`neighbours`, `beside`, `np.digitize`; built with -ffp-contract=off, so no fused multiply-adds),
the stable order by context, and the signs. The mask's spans are filled here too.

The functions take numpy arrays and the payload as buffers and check each one's length and item
size against the shapes passed (a mismatch is the caller's fault: ValueError). What the payload
says is never trusted: model ids, raw-bit reads and mask flips are checked before use, and the
tables' cumulative rows are checked to end at 2**24, so the class search stays inside its row.
A fault of the payload is returned as an error code (the constants below), with a detail such as
the missing model id in cursor[DETAIL], which Decoder.check turns into the one-line MzcError.

The decoder's state lives in two small arrays the functions update: `state` (one uint64: the
rANS state x) and `cursor` (int64: the words not yet read, the next raw bit, an error detail).
*/
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <string.h>

enum { OK, NO_TABLE, RAW_BITS_END, NOT_A_SIGN };               /* results: 0 = fine */
enum { WORDS_LEFT, BIT_POSITION, DETAIL, CURSOR_SLOTS };        /* the slots of `cursor` */

#define PRECISION 24                                            /* probabilities of 24 bits */
#define WORD_BITS 32

/* The payload's streams as one call of a kernel reads them; `store` writes x and the cursor back. */
typedef struct {
    uint64_t x;                     /* the rANS state */
    const unsigned char *words;     /* the 32-bit words, little-endian; read from the last one down */
    Py_ssize_t left;                /* words not yet read */
    const unsigned char *bits;      /* the raw bits, most significant bit of each byte first */
    Py_ssize_t bit_count, position; /* bits in all, the next one to read */
    const int64_t *cumulative;      /* per table a row of `width` cumulative frequencies B(s) */
    Py_ssize_t tables, width;
    uint64_t *state;
    int64_t *cursor;
} Stream;

/* The buffers of one call, released together however the call ends. */
typedef struct {
    Py_buffer views[10];
    int count;
} Views;

static void release(Views *views)
{
    for (int i = 0; i < views->count; i++)
        PyBuffer_Release(&views->views[i]);
}

/* Check that buffer `view` holds `count` items of `size` bytes (its item size that too, and
   aligned for them); -1 with a ValueError naming `name` if not. */
static int check_buffer(const Py_buffer *view, Py_ssize_t count, Py_ssize_t size, const char *name)
{
    if (view->itemsize != size || count < 0 || count > PY_SSIZE_T_MAX / size || view->len != count * size) {
        PyErr_Format(PyExc_ValueError, "%s: %zd bytes of %zd-byte items, expected %zd items of %zd bytes",
                     name, view->len, view->itemsize, count, size);
        return -1;
    }
    if ((uintptr_t)view->buf % (uintptr_t)size) {
        PyErr_Format(PyExc_ValueError, "%s is not aligned for %zd-byte items", name, size);
        return -1;
    }
    return 0;
}

/* The number of `size`-byte items in buffer `view` (checked as check_buffer does), or -1. */
static Py_ssize_t items(const Py_buffer *view, Py_ssize_t size, const char *name)
{
    if (view->itemsize != size || view->len % size) {
        PyErr_Format(PyExc_ValueError, "%s: %zd bytes of %zd-byte items, expected %zd-byte items", name, view->len,
                     view->itemsize, size);
        return -1;
    }
    return check_buffer(view, view->len / size, size, name) ? -1 : view->len / size;
}

/* The stream of buffers state (1 uint64), cursor (3 int64), words (uint32 items, read as
   little-endian bytes), bits (bytes) and cumulative (rows of `width` int64); -1 with a
   ValueError when a buffer or the cursor does not fit, or a cumulative row is not 0 at its
   start, nondecreasing and 2**24 at its end. */
static int open_stream(Stream *s, Py_buffer *state, Py_buffer *cursor, Py_buffer *words, Py_buffer *bits,
                       Py_buffer *cumulative, Py_ssize_t width)
{
    Py_ssize_t entries;
    if (check_buffer(state, 1, 8, "state") || check_buffer(cursor, CURSOR_SLOTS, 8, "cursor")
            || (entries = items(cumulative, 8, "cumulative")) < 0)
        return -1;
    if (words->itemsize != 4 || words->len % 4 || bits->itemsize != 1 || bits->len > PY_SSIZE_T_MAX / 8 || width < 2) {
        PyErr_SetString(PyExc_ValueError, "words not of 4-byte items, bits not of bytes, or cumulative rows under 2");
        return -1;
    }
    s->state = state->buf;
    s->cursor = cursor->buf;
    s->x = s->state[0];
    s->words = words->buf;
    s->left = s->cursor[WORDS_LEFT];
    s->bits = bits->buf;
    s->bit_count = 8 * bits->len;
    s->position = s->cursor[BIT_POSITION];
    s->cumulative = cumulative->buf;
    s->width = width;
    s->tables = entries / width;
    if (entries % width || s->left < 0 || s->left > words->len / 4 || s->position < 0 || s->position > s->bit_count) {
        PyErr_SetString(PyExc_ValueError, "cumulative not whole rows, or the cursor outside the words or bits");
        return -1;
    }
    for (Py_ssize_t t = 0; t < s->tables; t++) {
        const int64_t *row = s->cumulative + t * width;
        int rising = row[0] == 0 && row[width - 1] == (int64_t)1 << PRECISION;
        for (Py_ssize_t k = 1; k < width && rising; k++)
            rising = row[k - 1] <= row[k];
        if (!rising) {
            PyErr_Format(PyExc_ValueError, "cumulative row %zd does not rise from 0 to 2**%d", t, PRECISION);
            return -1;
        }
    }
    return 0;
}

static void store(const Stream *s)
{
    s->state[0] = s->x;
    s->cursor[WORDS_LEFT] = s->left;
    s->cursor[BIT_POSITION] = s->position;
}

/* x = (x << 32) | the next word when x < 2**32 and words remain (after each symbol). */
static inline void refill(Stream *s)
{
    if (s->x < (uint64_t)1 << WORD_BITS && s->left > 0) {
        const unsigned char *w = s->words + 4 * --s->left;
        s->x = (s->x << WORD_BITS) | ((uint64_t)w[0] | (uint64_t)w[1] << 8 | (uint64_t)w[2] << 16 | (uint64_t)w[3] << 24);
    }
}

/* One class of table `model` (a checked id): m = x mod 2**24, the class s with B(s) <= m < B(s+1),
   x = F(s) (x >> 24) + m - B(s), then x = (x << 32) | the next word when x < 2**32 and words remain.
   The row ends at 2**24 > m, so the search stops inside it. */
static inline int64_t decode_class(Stream *s, int64_t model)
{
    const int64_t *row = s->cumulative + model * s->width;
    uint64_t m = s->x & (((uint64_t)1 << PRECISION) - 1);
    int64_t k = 0;
    while ((uint64_t)row[k + 1] <= m)
        k++;
    s->x = (uint64_t)(row[k + 1] - row[k]) * (s->x >> PRECISION) + (m - (uint64_t)row[k]);
    refill(s);
    return k;
}

static inline int next_bit(Stream *s)
{
    int bit = (s->bits[s->position >> 3] >> (7 - (s->position & 7))) & 1;
    s->position++;
    return bit;
}

/* The values of `count` classes, in place: the sign bit first where `is_signed`, then the bits of
   |v| below its leading one; RAW_BITS_END, reading nothing, when the bits run out. */
static int take_raw_bits(Stream *s, int64_t *values, Py_ssize_t count, int is_signed)
{
    Py_ssize_t need = 0;
    for (Py_ssize_t i = 0; i < count; i++)
        if (values[i] > 0)
            need += values[i] - 1 + is_signed;   /* classes are < 48: no overflow */
    if (need > s->bit_count - s->position)
        return RAW_BITS_END;
    for (Py_ssize_t i = 0; i < count; i++) {
        int64_t k = values[i];
        if (k == 0)
            continue;
        int negative = is_signed && next_bit(s);
        int64_t value = 1;
        for (int64_t j = 1; j < k; j++)
            value = (value << 1) | next_bit(s);
        values[i] = negative ? -value : value;
    }
    return OK;
}

/* read_values(state, cursor, words, bits, cumulative, width, model, count, out): `count` signed
   values of table `model` into `out` (int64); NO_TABLE (model in cursor[DETAIL]) when there is no
   such table and count > 0. */
static PyObject *read_values(PyObject *self, PyObject *args)
{
    Views v = {.count = 6};
    Py_ssize_t width, model, count;
    Stream s;
    int code = OK;
    if (!PyArg_ParseTuple(args, "w*w*y*y*y*nnnw*", &v.views[0], &v.views[1], &v.views[2], &v.views[3],
                          &v.views[4], &width, &model, &count, &v.views[5]))
        return NULL;
    if (open_stream(&s, &v.views[0], &v.views[1], &v.views[2], &v.views[3], &v.views[4], width)
            || check_buffer(&v.views[5], count, 8, "out")) {
        release(&v);
        return NULL;
    }
    int64_t *out = v.views[5].buf;
    if (count > 0 && (model < 0 || model >= s.tables)) {
        s.cursor[DETAIL] = model;
        code = NO_TABLE;
    } else {
        for (Py_ssize_t i = 0; i < count; i++)
            out[i] = decode_class(&s, model);
        code = take_raw_bits(&s, out, count, 1);
    }
    store(&s);
    release(&v);
    return PyLong_FromLong(code);
}

/* How many of the increasing `thresholds` are <= a, as np.digitize (all of them for NaN). */
static inline int64_t context_of(double a, const double *thresholds, Py_ssize_t count)
{
    int64_t k = 0;
    while (k < count && !(a < thresholds[k]))
        k++;
    return k;
}

static inline int64_t sign_of(int64_t value)
{
    return (value > 0) - (value < 0);
}

static inline double magnitude(int64_t value)   /* |value| as binary64; decoded values are < 2**47 */
{
    return (double)(value < 0 ? -value : value);
}

/* The arrays a row works in (each `cols` long, `starts` one per context + 2): its passes' cells,
   and |q| of the two rows above as binary64 (zeros above row 0). */
typedef struct {
    int64_t *cells, *contexts, *ordered, *models, *values, *predicted, *starts;
    double *above, *above2;
} Scratch;

/* Decode the `count` values of one pass (columns `cells`, contexts `contexts`) into row `out`:
   their classes in the order of a stable counting sort by context (left to right within one),
   model first_model + context, then their raw bits (unsigned where signs follow). */
static int decode_pass(Stream *s, Scratch *w, Py_ssize_t count, int64_t contexts, int64_t first_model,
                       int is_signed, int64_t *out)
{
    memset(w->starts, 0, (size_t)(contexts + 1) * sizeof(int64_t));
    for (Py_ssize_t i = 0; i < count; i++)
        w->starts[w->contexts[i] + 1]++;
    for (int64_t k = 1; k <= contexts; k++)
        w->starts[k] += w->starts[k - 1];
    for (Py_ssize_t i = 0; i < count; i++) {
        int64_t at = w->starts[w->contexts[i]]++;
        w->ordered[at] = w->cells[i];
        w->models[at] = first_model + w->contexts[i];
    }
    for (Py_ssize_t i = 0; i < count; i++)
        w->values[i] = decode_class(s, w->models[i]);
    int code = take_raw_bits(s, w->values, count, is_signed);
    if (code != OK)
        return code;
    for (Py_ssize_t i = 0; i < count; i++)
        out[w->ordered[i]] = w->values[i];
    return OK;
}

/* The sign symbols of one pass's nonzero values in row r of `out` (left to right), each with
   table first_sign_model + its sign context, applied to them; NO_TABLE or NOT_A_SIGN on a fault. */
static int decode_signs(Stream *s, Scratch *w, Py_ssize_t count, Py_ssize_t r, Py_ssize_t cols, int odd,
                        int64_t *out, const int64_t *parent, const int weights[3], int64_t first_sign_model,
                        int64_t sign_contexts)
{
    int64_t *row = out + r * cols;
    Py_ssize_t nonzero = 0;
    int64_t top = 0;
    for (Py_ssize_t i = 0; i < count; i++) {
        int64_t c = w->cells[i];
        if (row[c] == 0)
            continue;
        int64_t side = odd ? sign_of(row[c - 1]) + (c + 1 < cols ? sign_of(row[c + 1]) : 0) : 0;
        int64_t above = r >= 1 ? sign_of(row[c - cols]) : 0;
        int64_t score = weights[0] * above + weights[1] * sign_of(parent[r * cols + c]) + weights[2] * side;
        int64_t k = (score < 0 ? -score : score);
        k = (k < sign_contexts - 1 ? k : sign_contexts - 1) + sign_contexts * odd;
        w->ordered[nonzero] = c;
        w->models[nonzero] = first_sign_model + k;
        w->predicted[nonzero] = score >= 0 ? 1 : -1;
        top = top > first_sign_model + k ? top : first_sign_model + k;
        nonzero++;
    }
    if (nonzero == 0)
        return OK;
    if (top >= s->tables) {
        s->cursor[DETAIL] = top;
        return NO_TABLE;
    }
    for (Py_ssize_t i = 0; i < nonzero; i++)
        w->values[i] = decode_class(s, w->models[i]);
    int code = take_raw_bits(s, w->values, nonzero, 0);
    if (code != OK)
        return code;
    for (Py_ssize_t i = 0; i < nonzero; i++)
        if (w->values[i] > 1)
            return NOT_A_SIGN;
    for (Py_ssize_t i = 0; i < nonzero; i++)
        row[w->ordered[i]] *= w->predicted[i] * (1 - 2 * w->values[i]);
    return OK;
}

/* The row loop of decode_rows (its buffers checked): OK or an error code. */
static int rows_loop(Stream *s, Scratch *w, Py_ssize_t rows, Py_ssize_t cols, const unsigned char *where,
                     const double *active, const double *thresholds, Py_ssize_t threshold_count,
                     int64_t first_model, const int64_t *parent, const int weights[3], int64_t first_sign_model,
                     int64_t sign_contexts, int64_t *out)
{
    memset(w->above, 0, (size_t)cols * sizeof(double));
    memset(w->above2, 0, (size_t)cols * sizeof(double));
    for (Py_ssize_t r = 0; r < rows; r++) {
        int64_t *row = out + r * cols;
        for (int odd = 0; odd < 2; odd++) {
            Py_ssize_t count = 0;
            int64_t top = 0;
            for (Py_ssize_t c = odd; c < cols; c += 2) {
                if (!where[r * cols + c])
                    continue;
                double n = w->above[c];   /* neighbours(row above, row two above), as numpy adds them */
                if (c >= 1)
                    n = n + 0.5 * w->above[c - 1];
                if (c + 1 < cols)
                    n = n + 0.5 * w->above[c + 1];
                n = n + 0.5 * w->above2[c];
                double a = active[r * cols + c] + n;
                if (odd) {   /* beside: the even columns left and right, just decoded */
                    double b = magnitude(row[c - 1]);
                    if (c + 1 < cols)
                        b = b + magnitude(row[c + 1]);
                    a = a + b;
                }
                int64_t k = context_of(a, thresholds, threshold_count);
                w->cells[count] = c;
                w->contexts[count] = k;
                top = top > k ? top : k;
                count++;
            }
            if (count == 0)
                continue;
            if (first_model + top >= s->tables) {
                s->cursor[DETAIL] = first_model + top;
                return NO_TABLE;
            }
            int code = decode_pass(s, w, count, threshold_count + 1, first_model, first_sign_model < 0, out + r * cols);
            if (code == OK && first_sign_model >= 0)
                code = decode_signs(s, w, count, r, cols, odd, out, parent, weights, first_sign_model, sign_contexts);
            if (code != OK)
                return code;
        }
        double *oldest = w->above2;
        w->above2 = w->above;
        w->above = oldest;
        for (Py_ssize_t c = 0; c < cols; c++)
            w->above[c] = magnitude(row[c]);
    }
    return OK;
}

/* decode_rows(state, cursor, words, bits, cumulative, width, rows, cols, where, active, thresholds,
   first_model, parent, (wa, wp, wt), first_sign_model, sign_contexts, out): the inverse of the
   row-by-row context coding (encode_bands, encode_corrections) into `out` (rows x cols int64 of
   zeros, left 0 outside `where`, rows x cols bools; `active` rows x cols binary64); OK or an error code.

   Each row comes in two passes, its even columns then its odd ones; a pass decodes its values by
   context (table first_model + context), left to right within one. The context counts the
   `thresholds` <= a, with a = active + n (+ b in odd columns) in the binary64 operations of
   `neighbours` and `beside`. With first_sign_model >= 0 (detail bands) the values are magnitudes,
   followed per pass by the sign symbols of its nonzero ones, predicted from the sign above, the
   `parent` (rows x cols int64; empty without signs) and the signs beside with the weights; the
   sign context is min(|score|, sign_contexts - 1), plus sign_contexts in odd columns. Without
   signs (first_sign_model -1) each value carries its sign in the raw bits. */
static PyObject *decode_rows(PyObject *self, PyObject *args)
{
    Views v = {.count = 10};
    Py_ssize_t width, rows, cols, thresholds;
    int first_model, first_sign_model, sign_contexts, weights[3];
    Stream s;
    if (!PyArg_ParseTuple(args, "w*w*y*y*y*nnny*y*y*iy*(iii)iiw*", &v.views[0], &v.views[1], &v.views[2],
                          &v.views[3], &v.views[4], &width, &rows, &cols, &v.views[5], &v.views[6], &v.views[7],
                          &first_model, &v.views[8], &weights[0], &weights[1], &weights[2], &first_sign_model,
                          &sign_contexts, &v.views[9]))
        return NULL;
    int signs = first_sign_model >= 0;
    Py_ssize_t cells = rows >= 0 && cols >= 0 && (cols == 0 || rows <= PY_SSIZE_T_MAX / 8 / cols) ? rows * cols : -1;
    if (open_stream(&s, &v.views[0], &v.views[1], &v.views[2], &v.views[3], &v.views[4], width)
            || check_buffer(&v.views[5], cells, 1, "where") || check_buffer(&v.views[6], cells, 8, "active")
            || (thresholds = items(&v.views[7], 8, "thresholds")) < 0
            || check_buffer(&v.views[8], signs ? cells : 0, 8, "parent") || check_buffer(&v.views[9], cells, 8, "out")) {
        release(&v);
        return NULL;
    }
    if (first_model < 0 || first_sign_model < -1 || (signs && sign_contexts < 1)) {
        release(&v);
        return PyErr_Format(PyExc_ValueError, "first model %d, first sign model %d, %d sign contexts", first_model,
                            first_sign_model, sign_contexts);
    }
    int code = OK;
    if (cells > 0) {
        /* cols <= the buffers' bytes / 8, so the slots' count cannot overflow */
        int64_t *slots = PyMem_Malloc(((size_t)cols * 8 + (size_t)thresholds + 2) * sizeof(int64_t));
        if (!slots) {
            release(&v);
            return PyErr_NoMemory();
        }
        Scratch w = {slots, slots + cols, slots + 2 * cols, slots + 3 * cols, slots + 4 * cols, slots + 5 * cols,
                     slots + 8 * cols, (double *)(slots + 6 * cols), (double *)(slots + 7 * cols)};
        code = rows_loop(&s, &w, rows, cols, v.views[5].buf, v.views[6].buf, v.views[7].buf, thresholds, first_model,
                         v.views[8].buf, weights, first_sign_model, sign_contexts, v.views[9].buf);
        PyMem_Free(slots);
    }
    store(&s);
    release(&v);
    return PyLong_FromLong(code);
}

/* A mask row of cols bytes: 1 between each pair of its n flips (checked to lie in 0..cols, in order), 0 elsewhere. */
static void fill_row(unsigned char *row, Py_ssize_t cols, const int64_t *flips, int64_t n)
{
    memset(row, 0, (size_t)cols);
    for (int64_t i = 0; i < n; i += 2)
        memset(row + flips[i], 1, (size_t)(flips[i + 1] - flips[i]));
}

/* fill_spans(lengths, unchanged, same, gaps, rows, cols, valid): the validity mask into `valid`
   (rows x cols bools) from each row's flips (`lengths`: int64 per row): where the row's `unchanged`
   (a bool per row), the row above's flips moved by the next values of `same`, else the next values
   of `gaps` (the first flip, then each flip minus the previous one minus 1); -1, or the
   first row whose flips leave 0..cols, do not increase, are odd in number, outrun their list or,
   `unchanged`, are not as many as the row above's (none above row 0). */
static PyObject *fill_spans(PyObject *self, PyObject *args)
{
    Views v = {.count = 5};
    Py_ssize_t rows, cols, same_count, new_count;
    if (!PyArg_ParseTuple(args, "y*y*y*y*nnw*", &v.views[0], &v.views[1], &v.views[2], &v.views[3], &rows, &cols,
                          &v.views[4]))
        return NULL;
    Py_ssize_t cells = rows >= 0 && cols >= 0 && (cols == 0 || rows <= PY_SSIZE_T_MAX / 8 / cols) ? rows * cols : -1;
    if (check_buffer(&v.views[0], rows, 8, "lengths") || check_buffer(&v.views[1], rows, 1, "unchanged")
            || (same_count = items(&v.views[2], 8, "same")) < 0 || (new_count = items(&v.views[3], 8, "gaps")) < 0
            || check_buffer(&v.views[4], cells, 1, "valid")) {
        release(&v);
        return NULL;
    }
    const int64_t *lengths = v.views[0].buf, *same = v.views[2].buf, *gaps = v.views[3].buf;
    const unsigned char *unchanged = v.views[1].buf;
    unsigned char *valid = v.views[4].buf;
    int64_t *flips = PyMem_Calloc((size_t)cols + 1, sizeof(int64_t));   /* the row above's flips, then the row's */
    if (!flips) {
        release(&v);
        return PyErr_NoMemory();
    }
    Py_ssize_t bad = -1, same_used = 0, new_used = 0;
    int64_t above = 0;   /* the row above's flip count */
    for (Py_ssize_t r = 0; r < rows; r++) {
        int64_t n = lengths[r];
        int moved = unchanged[r] != 0;
        const int64_t *values = moved ? same + same_used : gaps + new_used;
        if (n < 0 || n % 2 || n > cols + 1 || (moved && n != above)
                || n > (moved ? same_count - same_used : new_count - new_used)) {
            bad = r;
            break;
        }
        for (int64_t i = 0; i < n; i++) {
            int64_t low = i ? flips[i - 1] + 1 : 0;   /* the least this flip may be: flips increase */
            int64_t from = moved ? flips[i] : low;    /* the row above's flip, or the previous one + 1 */
            if (values[i] < low - from || values[i] > cols - from) {
                bad = r;
                break;
            }
            flips[i] = from + values[i];
        }
        if (bad >= 0)
            break;
        *(moved ? &same_used : &new_used) += n;
        above = n;
        fill_row(valid + r * cols, cols, flips, n);
    }
    PyMem_Free(flips);
    release(&v);
    return PyLong_FromSsize_t(bad);
}

/* ---- 8.0's mask: predicted flips through adaptive binary models (mzc/codecs/dwt2d/flips.py) */

enum { BIN_LIMIT = 1 << 16, PREFIX_BINS = 16, BINS = 2 + 2 * PREFIX_BINS, MAX_CLASS = 40 };
enum { COUNT_SET = 0, SAME_SET = 1, NEAR_SET = 19, GAP_SET = 21, SETS = 23 };

/* One binary decision of P(1) = f1 / 2**24 (0 < f1 < 2**24): class 0 takes [0, 2**24 - f1). */
static inline int decode_bit(Stream *s, uint64_t f1)
{
    uint64_t f0 = ((uint64_t)1 << PRECISION) - f1, m = s->x & (((uint64_t)1 << PRECISION) - 1);
    int bit = m >= f0;
    s->x = (bit ? f1 : f0) * (s->x >> PRECISION) + m - (bit ? f0 : 0);
    refill(s);
    return bit;
}

/* One decision of an adaptive model, counts[0..1] = (n0, n1): P(1) = floor((2 n1 + 1) 2**24 / (2 n + 2)),
   then the decided count + 1 while n < BIN_LIMIT. */
static inline int adaptive_bit(Stream *s, int64_t *counts)
{
    int64_t n = counts[0] + counts[1];
    int bit = decode_bit(s, (uint64_t)(((2 * counts[1] + 1) << PRECISION) / (2 * n + 2)));
    if (n < BIN_LIMIT)
        counts[bit]++;
    return bit;
}

/* One integer of the context set `set` (BINS count pairs): nonzero?, the sign where `is_signed`,
   the class k in unary, the top bit below the leading one by k, k - 1 bits of probability 1/2.
   -1 when the class passes MAX_CLASS. */
static inline int decode_integer(Stream *s, int64_t *set, int is_signed, int64_t *value)
{
    *value = 0;
    if (!adaptive_bit(s, set))
        return 0;
    int negative = is_signed && adaptive_bit(s, set + 2);
    int64_t k = 0, m = 1;
    while (adaptive_bit(s, set + 2 * (2 + (k < PREFIX_BINS - 1 ? k : PREFIX_BINS - 1))))
        if (++k > MAX_CLASS)
            return -1;
    if (k)
        m = 2 | adaptive_bit(s, set + 2 * (2 + PREFIX_BINS + (k < PREFIX_BINS - 1 ? k : PREFIX_BINS - 1)));
    for (int64_t j = 1; j < k; j++)
        m = (m << 1) | decode_bit(s, (uint64_t)1 << (PRECISION - 1));
    *value = negative ? -m : m;
    return 0;
}

static inline int64_t at_most(int64_t a, int64_t b) { return a < b ? a : b; }

/* One row's flips into `flips` (count n, the row above's in `above`, na of them), with each flip's
   move and residual (0 in a row not coded as moves); 0, or -1 when a value breaks the mask. */
static int decode_row(Stream *s, int64_t *counts, const int64_t *above, int64_t na, int64_t n, Py_ssize_t cols,
                      int64_t *flips, int64_t *moves, int64_t *residuals)
{
    int64_t v, low = 0;
    if (n && n == na) {
        for (int64_t i = 0; i < n; i++, low = flips[i - 1] + 1) {
            int64_t set = SAME_SET + i % 2 + 2 * (sign_of(residuals[i]) + 1) + 6 * (sign_of(moves[i]) + 1);
            if (decode_integer(s, counts + 2 * BINS * set, 1, &v)
                    || v < low - above[i] - moves[i] || v > cols - above[i] - moves[i])
                return -1;
            moves[i] += v;
            residuals[i] = v;
            flips[i] = above[i] + moves[i];
        }
        return 0;
    }
    int64_t next[2] = {0, 1};   /* per side, the first flip above not yet left of the row's last flip */
    for (int64_t i = 0; i < n; i++, low = flips[i - 1] + 1) {
        int64_t *j = &next[i % 2];
        while (*j < na && above[*j] < low)
            *j += 2;
        int near = *j < na;
        int64_t from = near ? above[*j] : low;
        if (decode_integer(s, counts + 2 * BINS * (near ? NEAR_SET + i % 2 : GAP_SET + at_most(i, 1)), near, &v)
                || v < low - from || v > cols - from)
            return -1;
        flips[i] = from + v;
        moves[i] = residuals[i] = 0;
    }
    return 0;
}

/* decode_flips(state, cursor, words, bits, cumulative, width, rows, cols, valid): 8.0's mask into
   `valid` (rows x cols bools), each row's span count as the change from the row above's, then its
   flips (decode_row); -1, or the first row whose count or flips are impossible. */
static PyObject *decode_flips(PyObject *self, PyObject *args)
{
    Views v = {.count = 6};
    Py_ssize_t width, rows, cols, bad = -1;
    Stream s;
    if (!PyArg_ParseTuple(args, "w*w*y*y*y*nnnw*", &v.views[0], &v.views[1], &v.views[2], &v.views[3],
                          &v.views[4], &width, &rows, &cols, &v.views[5]))
        return NULL;
    Py_ssize_t cells = rows >= 0 && cols >= 0 && (cols == 0 || rows <= PY_SSIZE_T_MAX / 8 / cols) ? rows * cols : -1;
    if (open_stream(&s, &v.views[0], &v.views[1], &v.views[2], &v.views[3], &v.views[4], width)
            || check_buffer(&v.views[5], cells, 1, "valid")) {
        release(&v);
        return NULL;
    }
    int64_t *counts = PyMem_Calloc(2 * BINS * SETS + 5 * ((size_t)cols + 2), sizeof(int64_t));
    if (!counts) {
        release(&v);
        return PyErr_NoMemory();
    }
    int64_t *above = counts + 2 * BINS * SETS, *flips = above + cols + 2, *moves = flips + cols + 2;
    int64_t *residuals = moves + cols + 2, na = 0, d;
    unsigned char *valid = v.views[5].buf;
    for (Py_ssize_t r = 0; r < rows && bad < 0; r++) {
        if (decode_integer(&s, counts, 1, &d) || d < -na / 2 || d > (cols + 1) / 2 - na / 2
                || decode_row(&s, counts, above, na, na + 2 * d, cols, flips, moves, residuals)) {
            bad = r;
            break;
        }
        na += 2 * d;
        memcpy(above, flips, (size_t)na * sizeof(int64_t));
        fill_row(valid + r * cols, cols, flips, na);
    }
    PyMem_Free(counts);
    store(&s);
    release(&v);
    return PyLong_FromSsize_t(bad);
}

static PyMethodDef methods[] = {
    {"read_values", read_values, METH_VARARGS, "Signed values of one model table (see _rows.c)."},
    {"decode_rows", decode_rows, METH_VARARGS, "A band or correction layer, row by row in two passes (see _rows.c)."},
    {"fill_spans", fill_spans, METH_VARARGS, "The validity mask from each row's flips (see _rows.c)."},
    {"decode_flips", decode_flips, METH_VARARGS, "8.0's mask: predicted flips, adaptive bits (see _rows.c)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "mzc.codecs.dwt2d._rows",
    "The compiled loops of the dwt2d payload decoder: rANS classes, raw bits, contexts, signs and mask spans.",
    -1, methods,
};

PyMODINIT_FUNC PyInit__rows(void)
{
    PyObject *m = PyModule_Create(&module);
    if (m && (PyModule_AddIntConstant(m, "OK", OK) || PyModule_AddIntConstant(m, "NO_TABLE", NO_TABLE)
              || PyModule_AddIntConstant(m, "RAW_BITS_END", RAW_BITS_END)
              || PyModule_AddIntConstant(m, "NOT_A_SIGN", NOT_A_SIGN)
              || PyModule_AddIntConstant(m, "WORDS_LEFT", WORDS_LEFT)
              || PyModule_AddIntConstant(m, "BIT_POSITION", BIT_POSITION)
              || PyModule_AddIntConstant(m, "DETAIL", DETAIL))) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
