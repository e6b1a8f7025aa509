/* The rasterizers of mzc/ops/raster.py and mzc/ops/rays.py: where the node lines of a grid meet
 * triangles, vertical lines (planar grids, by the inclusive barycentric test) and rays (central grids),
 * and the outermost hit of each node.
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
 * farthest(points, triangles, owners, boxes, xs, ys, columns, rows, cylindrical, tolerance, best) -> status
 *   points     float64 (n, 3): in the grid's frame (centre at the origin, axis along y)
 *   triangles  int64 (m, 3), corner indices checked to be in 0..n-1
 *   owners     int64 (k): the triangle of each box, checked to be in 0..m-1
 *   boxes      float64 (k, 2, 2): [[u_low, u_high], [v_low, v_high]], each triangle's candidate nodes
 *              (a NaN: none), found as front_most finds a triangle's block
 *   xs, ys     float64 (nx), (ny): uniform, increasing node coordinates u and v
 *   columns    float64 (2, nx): sine and cosine of each column's azimuth
 *   rows       float64 (2, ny): each row's cosine and sine of elevation (1 and 0 for cylindrical rays),
 *              so that a node's ray runs along (ring sin, rise, ring cos)
 *   cylindrical  nonzero: rays leave the axis at height v (ys), else the centre
 *   best       float64 (ny * nx): raised to the distance along the ray of every hit
 * Buffers are C-contiguous (y* and w*); their sizes, corner indices and owners are checked
 * before anything is read. Returns 0, or RASTER_BAD_SIZE or RASTER_BAD_INDEX, which raster.py
 * turns into errors.
 *
 * The operations are numpy's, in its order (-ffp-contract=off keeps them unfused), so the
 * results are the same bits as the vectorised forms that raster.py and rays.py had: with a step
 * s of the nodes (1 for a single node), a box's nodes run from ceil((min - nodes[0]) / s - 1e-7)
 * to floor((max - nodes[0]) / s + 1e-7), clipped to the nodes (a node on the box's edge is
 * always a candidate); with ab = b - a, ac = c - a and inverse = 1 / (ab.x ac.y - ab.y ac.x),
 *   u = ((x - a.x) ac.y - (y - a.y) ac.x) inverse,  v = ((y - a.y) ab.x - (x - a.x) ab.y) inverse,
 *   a hit when u, v and (1 - u) - v are all >= -tolerance (nodes on shared edges belong to both),
 *   z = (a.z + u ab.z) + v ac.z;
 * a triangle has an xy area when |ab.x ac.y - ab.y ac.x| > 1e-12 s^2, s the largest of
 * |ab.x|, |ab.y|, |ac.x|, |ac.y|. A ray from O = (0, v, 0) (v = 0 for spherical grids) along D
 * meets the triangle where its barycentric weights D . ((b - O) x (c - O)) and their cyclic
 * shifts, each times s = 1 / (D . n) (n = ab x ac; s finite), are all >= -tolerance, at the
 * distance t = (n . a - v n.y) s > 0 (n . a s for spherical grids); a weight is computed as
 * D . (b x c) - v D . (y x (c - b)) (D . (b x c) for spherical grids), in np.cross's order and
 * a fixed one for dot products (``cross``, ``dot``). The GIL is released while they run, on one thread.
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

/* Whether every corner index of the m triangles is a point, in 0..n-1. */
static int corners_in_range(const int64_t *triangles, Py_ssize_t m, Py_ssize_t n) {
    for (Py_ssize_t i = 0; i < 3 * m; i++)
        if (triangles[i] < 0 || triangles[i] >= n) return 0;
    return 1;
}

/* The corners c[0..8] of a triangle, from its three checked point indices. */
static void corners_of(const double *points, const int64_t *triangle, double *c) {
    for (int corner = 0; corner < 3; corner++)
        memcpy(c + 3 * corner, points + 3 * triangle[corner], 3 * sizeof(double));
}

/* The whole raster on checked sizes; RASTER_BAD_INDEX for a corner index out of range. */
static int raster(const double *points, Py_ssize_t n, const int64_t *triangles, Py_ssize_t m, const double *xs,
                  Py_ssize_t nx, const double *ys, Py_ssize_t ny, double tolerance, double *best) {
    if (!corners_in_range(triangles, m, n)) return RASTER_BAD_INDEX;
    for (Py_ssize_t t = 0; t < m; t++) {
        double c[9];
        corners_of(points, triangles + 3 * t, c);
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

/* p x q, as np.cross computes it. */
static void cross(const double *p, const double *q, double *out) {
    out[0] = p[1] * q[2] - p[2] * q[1];
    out[1] = p[2] * q[0] - p[0] * q[2];
    out[2] = p[0] * q[1] - p[1] * q[0];
}

/* p . q in one fixed order, (p0 q0 + p2 q2) + p1 q1 (the order numpy's einsum("ij,ij->i") took on x86-64 when
 * these grids were first computed, kept so that they stay the same bits), unfused on every CPU. */
static double dot(const double *p, const double *q) { return (p[0] * q[0] + p[2] * q[2]) + p[1] * q[1]; }

/* What the ray test needs of a triangle a, b, c: its normal n, n . a, the products b x c, c x a,
 * a x b and the shifts y x (c - b), y x (a - c), y x (b - a) that move their origin up the axis. */
typedef struct {
    double normal[3], offset, products[3][3], shifts[3][3];
} Facet;

/* The facet of the triangle of corners c[0..8]. */
static Facet facet_of(const double *c) {
    static const double axis[3] = {0.0, 1.0, 0.0};
    Facet f;
    double ab[3], ac[3], edges[3][3];
    for (int i = 0; i < 3; i++) {
        ab[i] = c[3 + i] - c[i];
        ac[i] = c[6 + i] - c[i];
        edges[0][i] = c[6 + i] - c[3 + i]; /* c - b */
        edges[1][i] = c[i] - c[6 + i];     /* a - c */
        edges[2][i] = c[3 + i] - c[i];     /* b - a */
    }
    cross(ab, ac, f.normal);
    f.offset = dot(f.normal, c);
    for (int i = 0; i < 3; i++) {
        cross(c + 3 * ((i + 1) % 3), c + 3 * ((i + 2) % 3), f.products[i]);
        cross(axis, edges[i], f.shifts[i]);
    }
    return f;
}

/* The node indices inside a box's [low, high], taken in either order as numpy's min and max would. */
static void box_range(const double *box, const double *nodes, Py_ssize_t count, int64_t *first, int64_t *last) {
    int reversed = box[1] < box[0]; /* false for a NaN, which node_range turns into no node */
    node_range(box[reversed], box[!reversed], nodes, count, first, last);
}

/* Raise best to the distance of every hit of the rays of nodes (rows, cols) in the block on facet f. */
static void cast_block(const Facet *f, int64_t row, int64_t row_last, int64_t col, int64_t col_last,
                       const double *ys, const double *sin_u, const double *cos_u, const double *ring,
                       const double *rise, int cylindrical, double least, Py_ssize_t nx, double *best) {
    for (int64_t r = row; r <= row_last; r++) {
        double v = cylindrical ? ys[r] : 0.0;
        for (int64_t k = col; k <= col_last; k++) {
            double direction[3] = {ring[r] * sin_u[k], rise[r], ring[r] * cos_u[k]};
            double scale = 1.0 / dot(direction, f->normal);
            if (!isfinite(scale)) continue; /* the ray runs along the triangle's plane */
            int inside = 1;
            for (int i = 0; i < 3; i++) {
                double weight = dot(direction, f->products[i]);
                if (cylindrical) weight -= v * dot(direction, f->shifts[i]);
                inside &= weight * scale >= least;
            }
            double t = (cylindrical ? f->offset - v * f->normal[1] : f->offset) * scale;
            if (inside && t > 0 && t > best[r * nx + k]) best[r * nx + k] = t;
        }
    }
}

/* Every box's candidate rays on checked sizes; RASTER_BAD_INDEX for a corner index or owner out of range. */
static int cast(const double *points, Py_ssize_t n, const int64_t *triangles, Py_ssize_t m, const int64_t *owners,
                const double *boxes, Py_ssize_t k, const double *xs, Py_ssize_t nx, const double *ys, Py_ssize_t ny,
                const double *columns, const double *rows, int cylindrical, double tolerance, double *best) {
    if (!corners_in_range(triangles, m, n)) return RASTER_BAD_INDEX;
    for (Py_ssize_t i = 0; i < k; i++)
        if (owners[i] < 0 || owners[i] >= m) return RASTER_BAD_INDEX;
    for (Py_ssize_t i = 0; i < k; i++) {
        int64_t col, col_last, row, row_last;
        box_range(boxes + 4 * i, xs, nx, &col, &col_last);
        box_range(boxes + 4 * i + 2, ys, ny, &row, &row_last);
        if (col > col_last || row > row_last) continue;
        double c[9];
        corners_of(points, triangles + 3 * owners[i], c);
        Facet f = facet_of(c);
        cast_block(&f, row, row_last, col, col_last, ys, columns, columns + nx, rows, rows + ny, cylindrical,
                   -tolerance, nx, best);
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

static PyObject *farthest(PyObject *self, PyObject *args) {
    (void)self;
    Py_buffer points, triangles, owners, boxes, xs, ys, columns, rows, best;
    int cylindrical;
    double tolerance;
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*y*y*y*pdw*", &points, &triangles, &owners, &boxes, &xs, &ys, &columns,
                          &rows, &cylindrical, &tolerance, &best))
        return NULL;
    const Py_ssize_t size = (Py_ssize_t)sizeof(double); /* and of an int64 */
    Py_ssize_t n = points.len / (3 * size), m = triangles.len / (3 * size), k = owners.len / size;
    Py_ssize_t nx = xs.len / size, ny = ys.len / size;
    int status = RASTER_BAD_SIZE;
    if (points.len == n * 3 * size && triangles.len == m * 3 * size && owners.len == k * size &&
        k <= PY_SSIZE_T_MAX / 32 &&
        boxes.len == k * 4 * size && xs.len == nx * size && ys.len == ny * size && columns.len == 2 * xs.len &&
        rows.len == 2 * ys.len && (nx == 0 || ny <= PY_SSIZE_T_MAX / 8 / nx) && best.len == nx * ny * size) {
        Py_BEGIN_ALLOW_THREADS
        status = cast(points.buf, n, triangles.buf, m, owners.buf, boxes.buf, k, xs.buf, nx, ys.buf, ny, columns.buf,
                      rows.buf, cylindrical, tolerance, best.buf);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&points);
    PyBuffer_Release(&triangles);
    PyBuffer_Release(&owners);
    PyBuffer_Release(&boxes);
    PyBuffer_Release(&xs);
    PyBuffer_Release(&ys);
    PyBuffer_Release(&columns);
    PyBuffer_Release(&rows);
    PyBuffer_Release(&best);
    return PyLong_FromLong(status);
}

static PyMethodDef methods[] = {
    {"front_most", front_most, METH_VARARGS,
     "front_most(points, triangles, xs, ys, tolerance, best) -> status: raise best to the heights of the hits."},
    {"heights", heights, METH_VARARGS,
     "heights(corners, owner, x, y, tolerance, z, hit) -> status: each point's height on its triangle's plane and "
     "whether it lies in the triangle."},
    {"farthest", farthest, METH_VARARGS,
     "farthest(points, triangles, owners, boxes, xs, ys, columns, rows, cylindrical, tolerance, best) -> status: "
     "raise best to the distances of the hits of the rays of each box's nodes on its triangle."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_raster",
                                    "The rasterizers: vertical lines and rays against triangles.",
                                    -1, methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__raster(void) { return PyModule_Create(&module); }
