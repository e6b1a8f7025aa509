/* The planar rasterizer (mzc/ops/raster.py): where vertical lines meet triangles, by the
 * inclusive barycentric test, and the front-most height of each node of a grid.
 *
 * front_most(points, triangles, xs, ys, tolerance, best) -> status
 *   points     float64 (n, 3); triangles int64 (m, 3), corner indices checked to be in 0..n-1
 *   xs, ys     float64 (nx), (ny): uniform, increasing node coordinates
 *   tolerance  how far outside the edges, in barycentric terms, a point still hits
 *   best       float64 (ny * nx): raised to the height of every hit (numpy's maximum: NaN stays)
 *   Each triangle's candidate nodes are the block of its xy box (``node_range``); a triangle
 *   whose xy projection has no area (seen edge-on) is skipped.
 * heights(corners, owner, x, y, tolerance, z, hit) -> status
 *   corners    float64 (m, 3, 3); owner int64 (k), a triangle for each point (x, y), float64 (k)
 *   z, hit     float64 (k), bool (k): written with the height of the triangle's plane there and
 *              whether the point lies in the triangle
 * ranges(values, width, nodes, out) -> status
 *   values     float64 (k, width): each row's [min, max] is mapped to node indices
 *   nodes      float64 (count): uniform, increasing
 *   out        int64 (2, k): written with each row's first and last node index inside it
 *              (empty: last < first), as ``node_range`` does for front_most; mzc.ops.rays uses it
 * Buffers are C-contiguous (y* and w*); their sizes, corner indices and owners are checked
 * before anything is read. Returns 0, or RASTER_BAD_SIZE or RASTER_BAD_INDEX, which raster.py
 * turns into errors.
 *
 * The operations are numpy's, in its order (-ffp-contract=off keeps them unfused), so the
 * results are the same bits as the vectorised form that raster.py had: with a step s of the
 * nodes (1 for a single node), a row's nodes run from ceil((min - nodes[0]) / s - 1e-7) to
 * floor((max - nodes[0]) / s + 1e-7), clipped to the nodes (a node on the box's edge is
 * always a candidate); with ab = b - a, ac = c - a and inverse = 1 / (ab.x ac.y - ab.y ac.x),
 *   u = ((x - a.x) ac.y - (y - a.y) ac.x) inverse,  v = ((y - a.y) ab.x - (x - a.x) ab.y) inverse,
 *   a hit when u, v and (1 - u) - v are all >= -tolerance (nodes on shared edges belong to both),
 *   z = (a.z + u ab.z) + v ac.z;
 * a triangle has an xy area when |ab.x ac.y - ab.y ac.x| > 1e-12 s^2, s the largest of
 * |ab.x|, |ab.y|, |ac.x|, |ac.y|. The GIL is released while they run, on one thread.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#include <stdint.h>
#include <string.h>

#define RASTER_BAD_SIZE 1
#define RASTER_BAD_INDEX 2

#define SLACK 1e-7 /* in node steps */

typedef struct {
    double ax, ay, az, abx, aby, abz, acx, acy, acz, inverse;
} Plane;

/* The plane of the triangle of corners c[0..8]. */
static Plane plane_of(const double *c) {
    Plane p = {c[0], c[1], c[2], c[3] - c[0], c[4] - c[1], c[5] - c[2], c[6] - c[0], c[7] - c[1], c[8] - c[2], 0.0};
    p.inverse = 1.0 / (p.abx * p.acy - p.aby * p.acx);
    return p;
}

/* Whether the triangle's xy projection has an area, relative to its own size. */
static int has_area(const Plane *p) {
    double scale = fmax(fmax(fabs(p->abx), fabs(p->aby)), fmax(fabs(p->acx), fabs(p->acy)));
    return fabs(p->abx * p->acy - p->aby * p->acx) > 1e-12 * (scale * scale);
}

/* Whether (x, y) lies in the triangle, within ``least`` (-tolerance); *z the height of its plane there. */
static int height_at(const Plane *p, double x, double y, double least, double *z) {
    double px = x - p->ax, py = y - p->ay;
    double u = (px * p->acy - py * p->acx) * p->inverse;
    double v = (py * p->abx - px * p->aby) * p->inverse;
    *z = p->az + u * p->abz + v * p->acz;
    return u >= least && v >= least && 1.0 - u - v >= least;
}

/* First and last node index inside [low, high] (none: *last < *first, also for a NaN). */
static void node_range(double low, double high, const double *nodes, Py_ssize_t count, int64_t *first,
                       int64_t *last) {
    *first = 0;
    *last = -1;
    if (count == 0 || isnan(low) || isnan(high)) return;
    double step = count > 1 ? nodes[1] - nodes[0] : 1.0;
    double start = ceil((low - nodes[0]) / step - SLACK), end = floor((high - nodes[0]) / step + SLACK);
    if (isnan(start) || isnan(end)) return;
    start = start < 0 ? 0 : (start > (double)count ? (double)count : start);
    end = end < -1 ? -1 : (end > (double)(count - 1) ? (double)(count - 1) : end);
    *first = (int64_t)start;
    *last = (int64_t)end;
}

static void raise_to(double *best, double z) {
    if (!isnan(*best) && (z > *best || isnan(z))) *best = z;
}

/* The whole raster on checked sizes; RASTER_BAD_INDEX for a corner index out of range. */
static int raster(const double *points, Py_ssize_t n, const int64_t *triangles, Py_ssize_t m, const double *xs,
                  Py_ssize_t nx, const double *ys, Py_ssize_t ny, double tolerance, double *best) {
    for (Py_ssize_t i = 0; i < 3 * m; i++)
        if (triangles[i] < 0 || triangles[i] >= n) return RASTER_BAD_INDEX;
    for (Py_ssize_t t = 0; t < m; t++) {
        double c[9];
        for (int corner = 0; corner < 3; corner++)
            memcpy(c + 3 * corner, points + 3 * triangles[3 * t + corner], 3 * sizeof(double));
        int64_t col, col_last, row, row_last;
        node_range(fmin(fmin(c[0], c[3]), c[6]), fmax(fmax(c[0], c[3]), c[6]), xs, nx, &col, &col_last);
        node_range(fmin(fmin(c[1], c[4]), c[7]), fmax(fmax(c[1], c[4]), c[7]), ys, ny, &row, &row_last);
        if (col > col_last || row > row_last) continue; /* no candidate node (most triangles of a fine mesh) */
        Plane plane = plane_of(c);
        if (!has_area(&plane)) continue;
        for (int64_t r = row; r <= row_last; r++)
            for (int64_t k = col; k <= col_last; k++) {
                double z;
                if (height_at(&plane, xs[k], ys[r], -tolerance, &z)) raise_to(&best[r * nx + k], z);
            }
    }
    return 0;
}

static PyObject *front_most(PyObject *self, PyObject *args) {
    (void)self;
    Py_buffer points, triangles, xs, ys, best;
    double tolerance;
    if (!PyArg_ParseTuple(args, "y*y*y*y*dw*", &points, &triangles, &xs, &ys, &tolerance, &best)) return NULL;
    const Py_ssize_t row = 3 * (Py_ssize_t)sizeof(double); /* int64 rows are as long */
    Py_ssize_t n = points.len / row, m = triangles.len / row;
    Py_ssize_t nx = xs.len / (Py_ssize_t)sizeof(double), ny = ys.len / (Py_ssize_t)sizeof(double);
    int status = RASTER_BAD_SIZE;
    if (points.len % row == 0 && triangles.len % row == 0 && xs.len % (Py_ssize_t)sizeof(double) == 0 &&
        ys.len % (Py_ssize_t)sizeof(double) == 0 && (nx == 0 || ny <= PY_SSIZE_T_MAX / 8 / nx) &&
        best.len == nx * ny * (Py_ssize_t)sizeof(double)) {
        Py_BEGIN_ALLOW_THREADS
        status = raster(points.buf, n, triangles.buf, m, xs.buf, nx, ys.buf, ny, tolerance, best.buf);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&points);
    PyBuffer_Release(&triangles);
    PyBuffer_Release(&xs);
    PyBuffer_Release(&ys);
    PyBuffer_Release(&best);
    return PyLong_FromLong(status);
}

static PyObject *heights(PyObject *self, PyObject *args) {
    (void)self;
    Py_buffer corners, owners, xs, ys, zs, hits;
    double tolerance;
    if (!PyArg_ParseTuple(args, "y*y*y*y*dw*w*", &corners, &owners, &xs, &ys, &tolerance, &zs, &hits)) return NULL;
    Py_ssize_t m = corners.len / (9 * (Py_ssize_t)sizeof(double)), k = owners.len / (Py_ssize_t)sizeof(int64_t);
    int status = RASTER_BAD_SIZE;
    if (corners.len == m * 9 * (Py_ssize_t)sizeof(double) && owners.len == k * (Py_ssize_t)sizeof(int64_t) &&
        xs.len == k * (Py_ssize_t)sizeof(double) && ys.len == xs.len && zs.len == xs.len && hits.len == k) {
        const double *c = corners.buf, *x = xs.buf, *y = ys.buf;
        const int64_t *owner = owners.buf;
        double *z = zs.buf;
        unsigned char *hit = hits.buf;
        Py_BEGIN_ALLOW_THREADS
        status = 0;
        for (Py_ssize_t i = 0; i < k && !status; i++)
            if (owner[i] < 0 || owner[i] >= m) status = RASTER_BAD_INDEX;
        for (Py_ssize_t i = 0; i < k && !status; i++) {
            Plane plane = plane_of(c + 9 * owner[i]);
            hit[i] = (unsigned char)height_at(&plane, x[i], y[i], -tolerance, &z[i]);
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&corners);
    PyBuffer_Release(&owners);
    PyBuffer_Release(&xs);
    PyBuffer_Release(&ys);
    PyBuffer_Release(&zs);
    PyBuffer_Release(&hits);
    return PyLong_FromLong(status);
}

static PyObject *ranges(PyObject *self, PyObject *args) {
    (void)self;
    Py_buffer values, nodes, out;
    Py_ssize_t width;
    if (!PyArg_ParseTuple(args, "y*ny*w*", &values, &width, &nodes, &out)) return NULL;
    Py_ssize_t k = width > 0 ? values.len / (width * (Py_ssize_t)sizeof(double)) : 0;
    Py_ssize_t count = nodes.len / (Py_ssize_t)sizeof(double);
    int status = RASTER_BAD_SIZE;
    if (width > 0 && width <= PY_SSIZE_T_MAX / 8 && values.len == k * width * (Py_ssize_t)sizeof(double) &&
        nodes.len == count * (Py_ssize_t)sizeof(double) && out.len == 2 * k * (Py_ssize_t)sizeof(int64_t)) {
        const double *v = values.buf, *x = nodes.buf;
        int64_t *range = out.buf;
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t i = 0; i < k; i++) {
            const double *row = v + i * width;
            double low = row[0], high = row[0];
            for (Py_ssize_t j = 1; j < width; j++) { /* numpy's min and max: a NaN wins */
                low = (row[j] < low || isnan(row[j])) && !isnan(low) ? row[j] : low;
                high = (row[j] > high || isnan(row[j])) && !isnan(high) ? row[j] : high;
            }
            node_range(low, high, x, count, &range[i], &range[k + i]);
        }
        status = 0;
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&values);
    PyBuffer_Release(&nodes);
    PyBuffer_Release(&out);
    return PyLong_FromLong(status);
}

static PyMethodDef methods[] = {
    {"front_most", front_most, METH_VARARGS,
     "front_most(points, triangles, xs, ys, tolerance, best) -> status: raise best to the heights of the hits."},
    {"heights", heights, METH_VARARGS,
     "heights(corners, owner, x, y, tolerance, z, hit) -> status: each point's height on its triangle's plane and "
     "whether it lies in the triangle."},
    {"ranges", ranges, METH_VARARGS,
     "ranges(values, width, nodes, out) -> status: each row's first and last node index within its [min, max]."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_raster",
                                    "The planar rasterizer: vertical lines against triangles.",
                                    -1, methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__raster(void) { return PyModule_Create(&module); }
