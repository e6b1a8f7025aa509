/* The planar rasterizer's arithmetic (mzc/ops/raster.py): where a vertical line (x, y) meets
 * a triangle, by the inclusive barycentric test, and the front-most height of each node.
 *
 * front_most(rows, col_range, row_range, xs, ys, tolerance, best) -> status
 *   rows       float64 (3, 3, m): coordinate i of corner j of triangle t at [i, j, t]
 *              (vectors.corner_rows); a triangle whose xy projection has no area is skipped
 *   col_range  int64 (2, m): each triangle's first and last candidate column (none if last < first)
 *   row_range  int64 (2, m): the same of rows
 *   xs, ys     float64 (nx), (ny): the nodes' coordinates
 *   tolerance  how far outside the edges, in barycentric terms, a point still hits
 *   best       float64 (ny * nx): raised to the height of every hit (numpy's maximum: NaN stays)
 * heights(rows, owner, x, y, tolerance, z, hit) -> status
 *   owner      int64 (k): a triangle of rows for each point (x, y), float64 (k) each
 *   z, hit     float64 (k), bool (k): written with the height of the triangle's plane there and
 *              whether the point lies in the triangle
 * Buffers are C-contiguous (y* and w*); their sizes, the ranges (within the nodes) and the
 * owners (within the triangles) are checked before anything is read. Returns 0, or
 * RASTER_BAD_SIZE or RASTER_BAD_INDEX, which raster.py turns into errors.
 *
 * The operations are numpy's, in its order (-ffp-contract=off keeps them unfused), so the
 * heights are the same bits as the vectorised form that raster.py had: with
 * ab = b - a, ac = c - a and inverse = 1 / (ab.x ac.y - ab.y ac.x),
 *   u = ((x - a.x) ac.y - (y - a.y) ac.x) inverse,  v = ((y - a.y) ab.x - (x - a.x) ab.y) inverse,
 *   hit when u, v and (1 - u) - v are all >= -tolerance (nodes on shared edges belong to both),
 *   z = (a.z + u ab.z) + v ac.z.
 * The GIL is released while they run, on one thread.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#include <stdint.h>

#define RASTER_BAD_SIZE 1
#define RASTER_BAD_INDEX 2

typedef struct {
    double ax, ay, az, abx, aby, abz, acx, acy, acz, inverse;
} Plane;

/* The plane of triangle t of the m triangles of ``rows``. */
static Plane plane_of(const double *rows, Py_ssize_t m, Py_ssize_t t) {
    const double *x = rows + t, *y = x + 3 * m, *z = y + 3 * m; /* corner j of a coordinate at [j * m] */
    Plane p = {x[0], y[0], z[0], x[m] - x[0], y[m] - y[0], z[m] - z[0], x[2 * m] - x[0], y[2 * m] - y[0],
               z[2 * m] - z[0], 0.0};
    p.inverse = 1.0 / (p.abx * p.acy - p.aby * p.acx);
    return p;
}

/* Whether the triangle's xy projection has an area, relative to its own size: twice its area
 * above 1e-12 of the square of its longest xy edge-coordinate from corner a. */
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

/* A range [first, last] of node indices: empty, or within 0..count-1. */
static int range_fits(int64_t first, int64_t last, int64_t count) {
    return last < first || (first >= 0 && last < count);
}

static void raise_to(double *best, double z) {
    if (!isnan(*best) && (z > *best || isnan(z))) *best = z;
}

static PyObject *front_most(PyObject *self, PyObject *args) {
    (void)self;
    Py_buffer corners, cols, rows, xs, ys, best;
    double tolerance;
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*dw*", &corners, &cols, &rows, &xs, &ys, &tolerance, &best)) return NULL;
    Py_ssize_t m = corners.len / (9 * (Py_ssize_t)sizeof(double));
    Py_ssize_t nx = xs.len / (Py_ssize_t)sizeof(double), ny = ys.len / (Py_ssize_t)sizeof(double);
    int status = RASTER_BAD_SIZE;
    if (corners.len == m * 9 * (Py_ssize_t)sizeof(double) && cols.len == 2 * m * (Py_ssize_t)sizeof(int64_t) &&
        rows.len == cols.len && xs.len == nx * (Py_ssize_t)sizeof(double) &&
        ys.len == ny * (Py_ssize_t)sizeof(double) && (nx == 0 || ny <= PY_SSIZE_T_MAX / 8 / nx) &&
        best.len == nx * ny * (Py_ssize_t)sizeof(double)) {
        const double *c = corners.buf, *x = xs.buf, *y = ys.buf;
        const int64_t *col = cols.buf, *row = rows.buf;
        double *out = best.buf;
        Py_BEGIN_ALLOW_THREADS
        status = 0;
        for (Py_ssize_t t = 0; t < m && !status; t++)
            if (!range_fits(col[t], col[m + t], nx) || !range_fits(row[t], row[m + t], ny)) status = RASTER_BAD_INDEX;
        for (Py_ssize_t t = 0; t < m && !status; t++) {
            Plane plane = plane_of(c, m, t);
            if (!has_area(&plane)) continue;
            for (int64_t r = row[t]; r <= row[m + t]; r++)
                for (int64_t k = col[t]; k <= col[m + t]; k++) {
                    double z;
                    if (height_at(&plane, x[k], y[r], -tolerance, &z)) raise_to(&out[r * nx + k], z);
                }
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&corners);
    PyBuffer_Release(&cols);
    PyBuffer_Release(&rows);
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
            Plane plane = plane_of(c, m, owner[i]);
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

static PyMethodDef methods[] = {
    {"front_most", front_most, METH_VARARGS,
     "front_most(rows, col_range, row_range, xs, ys, tolerance, best) -> status: raise best to the heights of "
     "the hits."},
    {"heights", heights, METH_VARARGS,
     "heights(rows, owner, x, y, tolerance, z, hit) -> status: each point's height on its triangle's plane and "
     "whether it lies in the triangle."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_raster",
                                    "The planar rasterizer's arithmetic: vertical lines against triangles.",
                                    -1, methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__raster(void) { return PyModule_Create(&module); }
