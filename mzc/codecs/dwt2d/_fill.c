/* The hole fill's multigrid cycle and stencil (mzc.codecs.dwt2d.wavelet.laplace_fill).

   The numbers are those of the numpy code this replaced, operation for operation (the
   encoder's files stay the same bytes): a neighbour sum adds the four directions in
   order, each times its edge weight (none on the finest level); a half-sweep updates
   `block` nodes at a time from the values before the block (red nodes can neighbour
   each other across the seam of a periodic level with an odd column count); the
   restriction adds the fine residuals into their aggregates in node order.

   The levels come packed: sizes and red counts (int64, one per level, finest first),
   then, level after level, the neighbours (int32, 4 x size: slot `size` means none),
   the edge weights (float64, 4 x size, levels 1 on), the diagonals (float64) and the
   parents (int32, every level but the coarsest). The caller lends the work space (float64:
   three values per node of the coarser levels, and `block` more), taken again at every
   cycle: a big grid's fresh memory costs the kernel time to hand out. Every count is checked
   against the buffers and every index before use; a bad one gives FILL_BAD_LEVELS. */

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

enum { FILL_OK = 0, FILL_BAD_LEVELS = 1 };

typedef struct {
    Py_ssize_t size, red;
    const int32_t *neighbours;    /* 4 x size */
    const double *weights;        /* 4 x size, or NULL: every edge weighs 1 */
    const double *diagonal;       /* size */
    const int32_t *parent;        /* size, or NULL on the coarsest level */
    double *rhs, *correction, *second;   /* the next level's: right-hand side, two corrections */
} Level;

typedef struct {
    Level *levels;
    Py_ssize_t count, block, w_cycle;
    double overcorrection;
    double *scratch;              /* `block` values: a half-sweep's block before it is written */
    int status;
} Cycle;

/* The value of node j of v (size values): 0 for the none slot, FILL_BAD_LEVELS past it. */
static inline double value_at(const double *v, int32_t j, Py_ssize_t size, int *status)
{
    if (j >= 0 && j < size) return v[j];
    if (j != size) *status = FILL_BAD_LEVELS;
    return 0.0;
}

/* Node i's neighbours' values in v times the edge weights, directions added in order. */
static inline double neighbour_sum(const Level *level, const double *v, Py_ssize_t i, int *status)
{
    Py_ssize_t n = level->size;
    const int32_t *nb = level->neighbours;
    double total = value_at(v, nb[i], n, status);
    if (level->weights) {
        const double *w = level->weights;
        total *= w[i];
        for (int k = 1; k < 4; k++) {
            double term = value_at(v, nb[k * n + i], n, status);
            term *= w[k * n + i];
            total += term;
        }
    } else {
        for (int k = 1; k < 4; k++) total += value_at(v, nb[k * n + i], n, status);
    }
    return total;
}

/* out = the stencil applied to v: diagonal * v - the neighbour sum. */
static void apply(const Level *level, const double *v, double *out, int *status)
{
    for (Py_ssize_t i = 0; i < level->size; i++) {
        double product = level->diagonal[i] * v[i];
        out[i] = product - neighbour_sum(level, v, i, status);
    }
}

/* One Gauss-Seidel half-sweep on the red (0) or black (1) nodes of u, `block` nodes at a time. */
static void relax(Cycle *cycle, const Level *level, double *u, const double *b, int colour)
{
    Py_ssize_t start = colour == 0 ? 0 : level->red, stop = colour == 0 ? level->red : level->size;
    for (Py_ssize_t first = start; first < stop; first += cycle->block) {
        Py_ssize_t last = first + cycle->block < stop ? first + cycle->block : stop;
        for (Py_ssize_t i = first; i < last; i++) {
            double total = neighbour_sum(level, u, i, &cycle->status);
            total += b[i];
            cycle->scratch[i - first] = total / level->diagonal[i];
        }
        memcpy(u + first, cycle->scratch, (size_t)(last - first) * sizeof(double));
    }
}

/* u = the preconditioner's approximate solution of levels[index] u = b (u: size values). */
static void run_cycle(Cycle *cycle, Py_ssize_t index, const double *b, double *u)
{
    Level *level = &cycle->levels[index];
    Py_ssize_t n = level->size;
    if (index == cycle->count - 1) {   /* one node: exact */
        for (Py_ssize_t i = 0; i < n; i++) u[i] = b[i] / level->diagonal[i];
        return;
    }
    Level *coarse = &cycle->levels[index + 1];
    Py_ssize_t m = coarse->size;
    memset(u, 0, (size_t)n * sizeof(double));
    relax(cycle, level, u, b, 0);
    relax(cycle, level, u, b, 1);
    memset(level->rhs, 0, (size_t)m * sizeof(double));
    for (Py_ssize_t i = 0; i < n; i++) {
        int32_t p = level->parent[i];
        if (p < 0 || p >= m) { cycle->status = FILL_BAD_LEVELS; return; }
        double product = level->diagonal[i] * u[i];
        double image = product - neighbour_sum(level, u, i, &cycle->status);
        level->rhs[p] += b[i] - image;
    }
    run_cycle(cycle, index + 1, level->rhs, level->correction);
    if (index + 2 < cycle->count && m > cycle->w_cycle) {
        apply(coarse, level->correction, level->second, &cycle->status);
        for (Py_ssize_t j = 0; j < m; j++) level->rhs[j] -= level->second[j];
        run_cycle(cycle, index + 1, level->rhs, level->second);
        for (Py_ssize_t j = 0; j < m; j++) level->correction[j] += level->second[j];
    }
    for (Py_ssize_t i = 0; i < n; i++) {   /* parents were checked above */
        double step = cycle->overcorrection * level->correction[level->parent[i]];
        u[i] += step;
    }
    relax(cycle, level, u, b, 1);
    relax(cycle, level, u, b, 0);
}

/* Fill `levels` (count of them) from the packed buffers; FILL_BAD_LEVELS when they disagree. */
static int unpack(Level *levels, Py_ssize_t count, const Py_buffer *sizes, const Py_buffer *reds,
                  const Py_buffer *neighbours, const Py_buffer *weights, const Py_buffer *diagonals,
                  const Py_buffer *parents)
{
    const int64_t *size = sizes->buf, *red = reds->buf;
    Py_ssize_t nodes = 0, weighted = 0, parented = 0;
    for (Py_ssize_t l = 0; l < count; l++) {
        if (size[l] < 1 || size[l] >= INT32_MAX || red[l] < 0 || red[l] > size[l]) return FILL_BAD_LEVELS;
        if (nodes > PY_SSIZE_T_MAX / 8 - size[l]) return FILL_BAD_LEVELS;
        Level *level = &levels[l];
        level->size = (Py_ssize_t)size[l];
        level->red = (Py_ssize_t)red[l];
        level->neighbours = (const int32_t *)neighbours->buf + 4 * nodes;
        level->diagonal = (const double *)diagonals->buf + nodes;
        level->weights = l == 0 ? NULL : (const double *)weights->buf + 4 * weighted;
        level->parent = l == count - 1 ? NULL : (const int32_t *)parents->buf + parented;
        nodes += level->size;
        weighted += l == 0 ? 0 : level->size;
        parented += l == count - 1 ? 0 : level->size;
    }
    if (neighbours->len != (Py_ssize_t)(4 * nodes * sizeof(int32_t))
        || weights->len != (Py_ssize_t)(4 * weighted * sizeof(double))
        || diagonals->len != (Py_ssize_t)(nodes * sizeof(double))
        || parents->len != (Py_ssize_t)(parented * sizeof(int32_t)))
        return FILL_BAD_LEVELS;
    return FILL_OK;
}

static PyObject *fill_cycle(PyObject *self, PyObject *args)
{
    Py_buffer out, b, sizes, reds, neighbours, weights, diagonals, parents, space;
    Py_ssize_t block, w_cycle;
    double overcorrection;
    (void)self;
    if (!PyArg_ParseTuple(args, "w*y*y*y*y*y*y*y*w*nnd", &out, &b, &sizes, &reds, &neighbours, &weights, &diagonals,
                          &parents, &space, &block, &w_cycle, &overcorrection))
        return NULL;
    int status = FILL_BAD_LEVELS;
    Py_ssize_t count = sizes.len / (Py_ssize_t)sizeof(int64_t);
    Level *levels = NULL;
    if (count < 1 || sizes.len != count * (Py_ssize_t)sizeof(int64_t) || reds.len != sizes.len || block < 1)
        goto done;
    levels = calloc((size_t)count, sizeof(Level));
    if (!levels) { PyErr_NoMemory(); goto done; }
    status = unpack(levels, count, &sizes, &reds, &neighbours, &weights, &diagonals, &parents);
    if (status != FILL_OK) goto done;
    status = FILL_BAD_LEVELS;
    if (b.len != levels[0].size * (Py_ssize_t)sizeof(double) || out.len != b.len) goto done;
    Py_ssize_t coarse_nodes = 0;
    for (Py_ssize_t l = 1; l < count; l++) coarse_nodes += levels[l].size;
    if (block > PY_SSIZE_T_MAX / 8 - 3 * coarse_nodes || space.len != (3 * coarse_nodes + block) * (Py_ssize_t)sizeof(double))
        goto done;
    double *next = space.buf, *scratch = next + 3 * coarse_nodes;
    for (Py_ssize_t l = 0; l + 1 < count; l++) {
        Py_ssize_t m = levels[l + 1].size;
        levels[l].rhs = next;
        levels[l].correction = next + m;
        levels[l].second = next + 2 * m;
        next += 3 * m;
    }
    Cycle cycle = {levels, count, block, w_cycle, overcorrection, scratch, FILL_OK};
    Py_BEGIN_ALLOW_THREADS
    run_cycle(&cycle, 0, b.buf, out.buf);
    Py_END_ALLOW_THREADS
    status = cycle.status;
done:
    free(levels);
    PyBuffer_Release(&out); PyBuffer_Release(&b); PyBuffer_Release(&sizes); PyBuffer_Release(&reds);
    PyBuffer_Release(&neighbours); PyBuffer_Release(&weights); PyBuffer_Release(&diagonals);
    PyBuffer_Release(&parents); PyBuffer_Release(&space);
    if (PyErr_Occurred()) return NULL;
    return PyLong_FromLong(status);
}

static PyObject *fill_apply(PyObject *self, PyObject *args)
{
    Py_buffer out, v, neighbours, diagonal;
    (void)self;
    if (!PyArg_ParseTuple(args, "w*y*y*y*", &out, &v, &neighbours, &diagonal))
        return NULL;
    int status = FILL_BAD_LEVELS;
    Py_ssize_t n = diagonal.len / (Py_ssize_t)sizeof(double);
    if (diagonal.len == n * (Py_ssize_t)sizeof(double) && v.len == diagonal.len && out.len == diagonal.len
        && neighbours.len == 4 * n * (Py_ssize_t)sizeof(int32_t)) {
        Level level = {n, 0, neighbours.buf, NULL, diagonal.buf, NULL, NULL, NULL, NULL};
        status = FILL_OK;
        Py_BEGIN_ALLOW_THREADS
        apply(&level, v.buf, out.buf, &status);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&out); PyBuffer_Release(&v); PyBuffer_Release(&neighbours); PyBuffer_Release(&diagonal);
    return PyLong_FromLong(status);
}

static PyMethodDef methods[] = {
    {"cycle", fill_cycle, METH_VARARGS,
     "cycle(out, b, sizes, reds, neighbours, weights, diagonals, parents, space, block, w_cycle, overcorrection) -> "
     "status: "
     "out = one multigrid cycle's approximate solution of the finest level's system for b."},
    {"apply", fill_apply, METH_VARARGS,
     "apply(out, v, neighbours, diagonal) -> status: out = the finest level's stencil (unit weights) applied to v."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_fill", "The dwt2d hole fill's multigrid kernels.", -1,
                                    methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__fill(void)
{
    return PyModule_Create(&module);
}
