/* The loops of the zipper (mzc/ops/zipper.py): a mesh's boundary edges, each boundary vertex's
 * nearest, the walks of the gap's half-edges, and the triangles that fill the gap's faces.
 *
 * boundary(triangles, vertex_count, edges) -> count
 *   triangles  int64 (m, 3), corner indices checked to be in 0..vertex_count-1
 *   edges      int64 (3m, 3): written with the boundary edges (tail, head, triangle), tail ->
 *              head as their triangle runs them, in the order of the triangles' edges (0-1,
 *              1-2, 2-0 of each): the edges in one triangle only (no other runs them either way)
 *   Each vertex's outgoing edges are listed (a counting sort by tail), and each edge a -> b
 *   looks for b -> a among b's and for another a -> b among a's: O(m) for meshes of bounded
 *   valence.
 * nearest(points, reach, candidate, distance) -> None
 *   points     float64 (n, 3)
 *   reach      pairs of points with d . d < reach reach are near (d = p(w) - p(v), each
 *              product and sum an IEEE operation in that order)
 *   candidate  int64 (n, c), filled with n beforehand: written, in each row v, with the
 *              points w near v (v itself among them), least by (d . d, w) first
 *   distance   float64 (n, c), filled with inf beforehand: their d . d
 *   The points are put into cubic cells at least reach wide, sorted by their cells' numbers,
 *   so that each point's near ones lie in its cell's 27 (9 runs of 3 in that order), each
 *   put into its row's sorted list and the last falling off: O(n c) for a boundary of
 *   bounded density, the same rows in any order of the work.
 * walks(next, walk) -> count
 *   next       int64 (k): the half-edge after each (-1 for none, else in 0..k-1)
 *   walk       int64 (k): written with the walk of each, the weakly connected components of
 *              the graph of the nexts, numbered 0.. in the order of their first half-edges
 *   Returns the number of walks (a union-find).
 * fill(points, source, target, next, rungs, reference, edges, longest, rim, triangles, added) -> (triangles, points)
 *   points     float64 (n, 3): the vertices the faces run through
 *   source, target  int64 (k): each half-edge's first and last vertex, in 0..n-1
 *   next       int64 (k): the half-edge after each around its face (where its target is the
 *              next's source), -1 for none; no two have the same next
 *   rungs      the first rung: the half-edges before it are the boundary's (reversed), those
 *              after the rungs', rung i's a -> b as rungs + i, b -> a as rungs + (k - rungs) / 2 + i
 *   reference  float64 (k, 3): the normal of the surface on the other side of each half-edge
 *   edges      int64 (e, 2): the edges between the vertices that exist already (no new
 *              triangle may add one of them again)
 *   longest    the longest edge a filling may cut: a face on a rim that needs a longer one
 *              stays open, a gap between charts makes none (what is left is fanned)
 *   rim        bool (k): whether each half-edge's face lies on a rim (the same for a whole face)
 *   triangles  int64 (k, 3): written with the new triangles, over 0..n-1 and n + i for
 *              added point i
 *   added      float64 (k, 3): written with the points added
 *   Returns the numbers of triangles and points written.
 * Buffers are C-contiguous (y* and w*); sizes and indices are checked before anything is
 * used: ValueError for sizes, IndexError for an index out of range or a next given twice,
 * MemoryError. The GIL is released while they run, on one thread.
 *
 * Filling a face: its walk (the half-edges from the first in index order, following next; a
 * walk that does not come back to it is no face and stays open) is a polygon, its vertices
 * v1 ... vk as they run (the face on the left), a vertex twice where a chart's corner
 * touches the rest of it or a rung is walked both ways. A walk of the boundary's half-edges
 * alone runs round one chart's boundary: it is filled only as a hole in the chart, when its
 * vector area faces as the references of its edges do (their unit vectors summed), never
 * over the chart. The polygon is clipped ear by ear: the ear at v is the triangle u v w of
 * it and its neighbours, which adds the edge u w. An ear may not add an edge that exists (an
 * edge in three triangles) nor join a vertex to itself, and the one taken is the least by
 * (folds, cost): it folds when its normal makes more than acos(FACING) with the reference of
 * one of its two edges (a triangle laid back over the surface beside it) or with the
 * polygon's vector area (an ear turned over within a flat gap), or when it has no area; its
 * cost is the length of u w over its quality 4 sqrt(3) area / (sum of its squared sides), at
 * least QUALITY (1 for an equilateral triangle), so short cuts of well-shaped ears go first:
 * a long thin gap is zipped from its ends, ladder-like. Equal ears go by position. Clipping
 * an ear gives the new edge u w the ear's normal as reference and recomputes the ears at u
 * and w (a binary heap with stale entries skipped). The last cut, of a quad, is the one of
 * its two whose triangles fold least, against their edges' references and each other. What
 * is left with no ear that adds no existing edge (rare: both diagonals of a quad exist
 * elsewhere) is closed by fans about new points, the means of the vertices of each simple
 * cycle it runs: their edges are all new. On a gap between charts an ear whose cut is longer
 * than `longest` is not taken (a long cut across a wide gap, where many charts meet, lies far
 * inside a curved surface): what is left without another ear is fanned. A polygon on a rim
 * whose filling would cut longer is no gap between charts but a rim, or a hole of the
 * surface: it is left open (its triangles, points and edges taken back).
 *
 * Every triangle uses each half-edge of its face in the face's direction, and adds only
 * edges that do not exist, so no edge is ever in more than two triangles, and one in two
 * is run once each way. The arithmetic is IEEE operations in the order written
 * (-ffp-contract=off), the same on every CPU.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define FACING (-0.5) /* cosine between an ear's normal and a reference below which the ear folds */
#define QUALITY 0.05  /* the least quality an ear's cost divides by */
#define EMPTY UINT64_MAX
#define GONE (UINT64_MAX - 1) /* a key taken out again: searches go past it */

/* ---- an open-addressing set of undirected edges, keyed (low << 32) | high ---- */

typedef struct {
    uint64_t *keys;
    size_t mask;
} EdgeSet;

static uint64_t edge_key(int64_t a, int64_t b) {
    return a < b ? ((uint64_t)a << 32) | (uint64_t)b : ((uint64_t)b << 32) | (uint64_t)a;
}

static size_t slot_of(const EdgeSet *set, uint64_t key) {
    size_t slot = (size_t)((key * 0x9E3779B97F4A7C15ULL) >> 17) & set->mask;
    while (set->keys[slot] != EMPTY && set->keys[slot] != key) slot = (slot + 1) & set->mask;
    return slot;
}

static int has_edge(const EdgeSet *set, int64_t a, int64_t b) {
    return set->keys[slot_of(set, edge_key(a, b))] != EMPTY;
}

static void add_edge(EdgeSet *set, int64_t a, int64_t b) {
    uint64_t key = edge_key(a, b);
    set->keys[slot_of(set, key)] = key;
}

static void remove_edge(EdgeSet *set, int64_t a, int64_t b) {
    size_t slot = slot_of(set, edge_key(a, b));
    if (set->keys[slot] != EMPTY) set->keys[slot] = GONE;
}

/* A set for `count` edges (at most half full), or 0 without memory. */
static int edge_set(EdgeSet *set, size_t count) {
    size_t size = 16;
    while (size < 2 * count) size <<= 1;
    set->mask = size - 1;
    set->keys = malloc(size * sizeof(uint64_t));
    if (!set->keys) return 0;
    memset(set->keys, 0xff, size * sizeof(uint64_t));
    return 1;
}

/* ---- boundary edges ---- */

/* Writes the boundary edges of triangles t (m) over n vertices; their number, or -1 without memory. */
static Py_ssize_t boundary_edges(const int64_t *t, Py_ssize_t m, Py_ssize_t n, int64_t *edges) {
    int64_t *first = calloc((size_t)n + 1, sizeof(int64_t)), *out = malloc(3 * (size_t)m * sizeof(int64_t) + 1);
    if (!first || !out) {
        free(first);
        free(out);
        return -1;
    }
    for (Py_ssize_t e = 0; e < 3 * m; e++) first[t[e] + 1]++;
    for (Py_ssize_t v = 0; v < n; v++) first[v + 1] += first[v];
    for (Py_ssize_t e = 0; e < 3 * m; e++) {   /* edge e runs t[e] -> the next corner of its triangle */
        int64_t a = t[e], b = t[e % 3 == 2 ? e - 2 : e + 1];
        out[first[a]++] = b;
    }
    for (Py_ssize_t v = n; v > 0; v--) first[v] = first[v - 1];   /* back to the starts */
    first[0] = 0;
    Py_ssize_t count = 0;
    for (Py_ssize_t e = 0; e < 3 * m; e++) {
        int64_t a = t[e], b = t[e % 3 == 2 ? e - 2 : e + 1], j = first[b], runs = 0;
        while (j < first[b + 1] && out[j] != a) j++;
        for (int64_t i = first[a]; j == first[b + 1] && i < first[a + 1]; i++) runs += out[i] == b;
        if (runs == 1) {   /* no b -> a, and a -> b once */
            int64_t *edge = edges + 3 * count++;
            edge[0] = a;
            edge[1] = b;
            edge[2] = e / 3;
        }
    }
    free(first);
    free(out);
    return count;
}

static PyObject *boundary(PyObject *self, PyObject *args) {
    (void)self;
    Py_buffer triangles, edges;
    Py_ssize_t n;
    if (!PyArg_ParseTuple(args, "y*nw*", &triangles, &n, &edges)) return NULL;
    Py_ssize_t m = triangles.len / (3 * (Py_ssize_t)sizeof(int64_t)), count = -2;
    const int64_t *t = triangles.buf;
    if (triangles.len == 3 * m * (Py_ssize_t)sizeof(int64_t) && n >= 0 &&
        edges.len == 9 * m * (Py_ssize_t)sizeof(int64_t)) {
        count = -3;
        Py_ssize_t bad = 0;
        for (Py_ssize_t e = 0; e < 3 * m; e++) bad |= t[e] < 0 || t[e] >= n;
        if (!bad) {
            Py_BEGIN_ALLOW_THREADS
            count = boundary_edges(t, m, n, edges.buf);
            Py_END_ALLOW_THREADS
        }
    }
    PyBuffer_Release(&triangles);
    PyBuffer_Release(&edges);
    if (count == -1) return PyErr_NoMemory();
    if (count == -2) return PyErr_Format(PyExc_ValueError, "boundary: buffers whose sizes do not fit");
    if (count == -3) return PyErr_Format(PyExc_IndexError, "boundary: a corner index out of range");
    return PyLong_FromSsize_t(count);
}

/* ---- each boundary vertex's nearest ---- */

#define CELL_BITS 20   /* cells along each axis at most 2^20: a cell's key is its three numbers, 21 bits each */

typedef struct {
    uint64_t key;
    int64_t point;
} Celled;

static int by_key(const void *a, const void *b) {
    uint64_t x = ((const Celled *)a)->key, y = ((const Celled *)b)->key;
    return (x > y) - (x < y);
}

/* Puts w (d . d = squared) into v's row of c, kept least by (squared, number) first. */
static void keep_nearest(int64_t *row, double *far, Py_ssize_t c, int64_t w, double squared) {
    Py_ssize_t j = c;
    while (j > 0 && (far[j - 1] > squared || (far[j - 1] == squared && row[j - 1] > w))) j--;
    if (j == c) return;
    memmove(row + j + 1, row + j, (size_t)(c - j - 1) * sizeof(int64_t));
    memmove(far + j + 1, far + j, (size_t)(c - j - 1) * sizeof(double));
    row[j] = w;
    far[j] = squared;
}

/* The first of the n sorted cells whose key is at least key. */
static Py_ssize_t first_at(const Celled *cells, Py_ssize_t n, uint64_t key) {
    Py_ssize_t low = 0, high = n;
    while (low < high) {
        Py_ssize_t middle = low + (high - low) / 2;
        if (cells[middle].key < key) low = middle + 1;
        else high = middle;
    }
    return low;
}

/* Fills each row of the n points' candidate and distance tables (c columns); -1 without memory. */
static int nearest_points(const double *p, Py_ssize_t n, double reach, Py_ssize_t c, int64_t *candidate,
                          double *distance) {
    if (!n) return 0;
    Celled *cells = malloc((size_t)n * sizeof(Celled));
    if (!cells) return -1;
    double low[3], cell = reach;
    for (int k = 0; k < 3; k++) {
        double high = low[k] = p[k];
        for (Py_ssize_t v = 1; v < n; v++) {
            low[k] = fmin(low[k], p[3 * v + k]);
            high = fmax(high, p[3 * v + k]);
        }
        cell = fmax(cell, (high - low[k]) / (double)(1 << CELL_BITS));
    }
    cell *= 1.0 + 1e-6;   /* wider than reach by more than the rounding of the cells' numbers */
    for (Py_ssize_t v = 0; v < n; v++) {
        uint64_t key = 0;
        for (int k = 0; k < 3; k++) key = key << 21 | (uint64_t)((p[3 * v + k] - low[k]) / cell);
        cells[v].key = key;
        cells[v].point = v;
    }
    qsort(cells, (size_t)n, sizeof(Celled), by_key);
    double limit = reach * reach;
    for (Py_ssize_t start = 0, end; start < n; start = end) {
        uint64_t key = cells[start].key;
        for (end = start; end < n && cells[end].key == key; end++) {}
        int64_t at[3] = {(int64_t)(key >> 42), (int64_t)(key >> 21 & 0x1FFFFF), (int64_t)(key & 0x1FFFFF)};
        for (int around = 0; around < 9; around++) {   /* the cells z - 1 .. z + 1 of a column are neighbours in order */
            int64_t x = at[0] + around / 3 - 1, y = at[1] + around % 3 - 1, z = at[2] > 0 ? at[2] - 1 : 0;
            if (x < 0 || y < 0) continue;
            uint64_t column = (uint64_t)x << 42 | (uint64_t)y << 21, last = column | (uint64_t)(at[2] + 1);
            for (Py_ssize_t j = first_at(cells, n, column | (uint64_t)z); j < n && cells[j].key <= last; j++)
                for (Py_ssize_t i = start; i < end; i++) {
                    int64_t v = cells[i].point, w = cells[j].point;
                    double dx = p[3 * w] - p[3 * v], dy = p[3 * w + 1] - p[3 * v + 1], dz = p[3 * w + 2] - p[3 * v + 2];
                    double squared = dx * dx + dy * dy + dz * dz;
                    if (squared < limit) keep_nearest(candidate + v * c, distance + v * c, c, w, squared);
                }
        }
    }
    free(cells);
    return 0;
}

static PyObject *nearest(PyObject *self, PyObject *args) {
    (void)self;
    Py_buffer points, candidates, distances;
    double reach;
    if (!PyArg_ParseTuple(args, "y*dw*w*", &points, &reach, &candidates, &distances)) return NULL;
    const Py_ssize_t word = (Py_ssize_t)sizeof(int64_t);   /* and of a double */
    Py_ssize_t n = points.len / (3 * word), c = n ? candidates.len / (n * word) : 0;
    int status = 1;   /* 1: sizes or values, 3: memory */
    if (points.len == 3 * n * word && candidates.len == n * c * word && distances.len == n * c * word &&
        reach > 0 && isfinite(reach)) {
        const double *p = points.buf;
        status = 0;
        for (Py_ssize_t i = 0; i < 3 * n; i++) status |= !isfinite(p[i]);
    }
    if (!status) {
        Py_BEGIN_ALLOW_THREADS
        if (nearest_points(points.buf, n, reach, c, candidates.buf, distances.buf)) status = 3;
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&points);
    PyBuffer_Release(&candidates);
    PyBuffer_Release(&distances);
    if (status == 1)
        return PyErr_Format(PyExc_ValueError, "nearest: buffers whose sizes do not fit, or values not finite");
    if (status == 3) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

/* ---- the walks of the half-edges ---- */

/* The root of v's set, the path to it halved on the way. */
static int64_t root_of(int64_t *parent, int64_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
}

static PyObject *walks(PyObject *self, PyObject *args) {
    (void)self;
    Py_buffer nexts, walked;
    if (!PyArg_ParseTuple(args, "y*w*", &nexts, &walked)) return NULL;
    const Py_ssize_t word = (Py_ssize_t)sizeof(int64_t);
    Py_ssize_t k = nexts.len / word, count = 0;
    const int64_t *next = nexts.buf;
    int64_t *walk = walked.buf;
    int status = nexts.len == k * word && walked.len == k * word ? 0 : 1;   /* 1: sizes, 2: an index */
    for (Py_ssize_t h = 0; !status && h < k; h++)
        if (next[h] < -1 || next[h] >= k) status = 2;
    if (!status) {   /* walk serves as the parent of each in the union-find, then as its root's number */
        int64_t *number = malloc(((size_t)k + 1) * sizeof(int64_t));
        if (!number) status = 3;
        for (Py_ssize_t h = 0; !status && h < k; h++) walk[h] = h;
        for (Py_ssize_t h = 0; !status && h < k; h++) {
            if (next[h] < 0) continue;
            int64_t a = root_of(walk, h), b = root_of(walk, next[h]);
            if (a != b) walk[a > b ? a : b] = a < b ? a : b;   /* the lower root: each set's is its least */
        }
        for (Py_ssize_t h = 0; !status && h < k; h++) {
            int64_t root = root_of(walk, h);
            number[h] = root == h ? count++ : number[root];   /* a root is its set's least: numbered first */
        }
        if (!status) memcpy(walk, number, (size_t)k * sizeof(int64_t));
        free(number);
    }
    PyBuffer_Release(&nexts);
    PyBuffer_Release(&walked);
    if (status == 1) return PyErr_Format(PyExc_ValueError, "walks: buffers whose sizes do not fit");
    if (status == 2) return PyErr_Format(PyExc_IndexError, "walks: a next out of range");
    if (status == 3) return PyErr_NoMemory();
    return PyLong_FromSsize_t(count);
}

/* ---- filling the faces ---- */

typedef struct {
    int fold;
    double cost;
    int64_t at, version;
} Ear;

typedef struct {
    const double *p;          /* points (n, 3) */
    EdgeSet edges;
    int64_t *vertex, *prev, *next, *version;   /* per position of the cycle being clipped */
    double *reference;        /* per position: the reference of the edge to the next position */
    int64_t *cuts;            /* the edges added while a cycle is filled: (u, w) pairs */
    int64_t *stack, *depth;   /* fans' stack of positions, and per vertex where its is on it (-1) */
    int64_t *walked;          /* per vertex, where its half-edge is on a walk's stack (-1) */
    double longest;           /* the longest edge a filling may cut */
    int rim;                  /* whether the face at hand lies on a rim: left open, not fanned, past longest */
    double area[3];           /* the vector area of the cycle being filled: a reference for each ear */
    Py_ssize_t rungs, k;      /* the first rung's half-edge (those before are the boundary's), all */
    unsigned char *crossed;   /* per rung half-edge: whether the walk at hand crosses it (0) */
    Ear *heap;
    Py_ssize_t heap_size;
    int64_t *triangles;       /* output */
    Py_ssize_t triangle_count;
    double *added;            /* output */
    Py_ssize_t added_count, n;
} Filler;

static int ear_before(const Ear *a, const Ear *b) {
    if (a->fold != b->fold) return a->fold < b->fold;
    if (a->cost != b->cost) return a->cost < b->cost;
    return a->at < b->at;
}

static void push(Filler *f, Ear ear) {
    Py_ssize_t i = f->heap_size++;
    while (i > 0 && ear_before(&ear, &f->heap[(i - 1) / 2])) {
        f->heap[i] = f->heap[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    f->heap[i] = ear;
}

static Ear pop(Filler *f) {
    Ear top = f->heap[0], last = f->heap[--f->heap_size];
    Py_ssize_t i = 0;
    for (;;) {
        Py_ssize_t child = 2 * i + 1;
        if (child >= f->heap_size) break;
        if (child + 1 < f->heap_size && ear_before(&f->heap[child + 1], &f->heap[child])) child++;
        if (!ear_before(&f->heap[child], &last)) break;
        f->heap[i] = f->heap[child];
        i = child;
    }
    f->heap[i] = last;
    return top;
}

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* The normal (twice the area) of triangle u v w. */
static void normal_of(const double *p, int64_t u, int64_t v, int64_t w, double *normal) {
    const double *a = p + 3 * u, *b = p + 3 * v, *c = p + 3 * w;
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    normal[0] = ab[1] * ac[2] - ab[2] * ac[1];
    normal[1] = ab[2] * ac[0] - ab[0] * ac[2];
    normal[2] = ab[0] * ac[1] - ab[1] * ac[0];
}

static double distance2(const double *p, int64_t u, int64_t v) {
    const double *a = p + 3 * u, *b = p + 3 * v;
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    return dot3(d, d);
}

/* Whether the triangle of normal `normal` (length `size`) folds against a reference. */
static int folds(const double *normal, double size, const double *reference) {
    double length = sqrt(dot3(reference, reference));
    return length > 0 && dot3(normal, reference) < FACING * size * length;
}

/* Whether triangle u v w (positions) folds against the references of its edges u -> v and
   v -> w or the cycle's area, or has no area; its quality (at least QUALITY) and normal. */
static int ear_folds(Filler *f, int64_t u, int64_t v, int64_t w, double *quality, double *normal) {
    const int64_t *x = f->vertex;
    normal_of(f->p, x[u], x[v], x[w], normal);
    double size = sqrt(dot3(normal, normal));
    double sides = distance2(f->p, x[u], x[v]) + distance2(f->p, x[v], x[w]) + distance2(f->p, x[w], x[u]);
    *quality = sides > 0 ? 2.0 * sqrt(3.0) * size / sides : 0.0;
    if (*quality < QUALITY) *quality = QUALITY;
    return size == 0 || folds(normal, size, f->reference + 3 * u) || folds(normal, size, f->reference + 3 * v) ||
           folds(normal, size, f->area);
}

/* Pushes the ear at position i (unless it would add an existing edge, or on a gap between
   charts cut longer than f->longest). */
static void consider(Filler *f, int64_t i) {
    int64_t j = f->prev[i], k = f->next[i];
    f->version[i]++;
    if (f->vertex[j] == f->vertex[k] || has_edge(&f->edges, f->vertex[j], f->vertex[k])) return;
    double length = sqrt(distance2(f->p, f->vertex[j], f->vertex[k]));
    if (!f->rim && !(length <= f->longest)) return;
    double quality, normal[3];
    int fold = ear_folds(f, j, i, k, &quality, normal);
    Ear ear = {fold, length / quality, i, f->version[i]};
    push(f, ear);
}

/* The folds and cost of cutting the quad of positions a b c d along a c: its two triangles'
   folds against their edges' references and against each other; -1 if the cut exists or is
   longer than f->longest. */
static int quad_folds(Filler *f, int64_t a, int64_t b, int64_t c, int64_t d, double *cost) {
    const int64_t *x = f->vertex;
    double length = sqrt(distance2(f->p, x[a], x[c]));
    if (x[a] == x[c] || has_edge(&f->edges, x[a], x[c]) || !(length <= f->longest)) return -1;
    double first_quality, second_quality, first[3], second[3];
    int count = ear_folds(f, a, b, c, &first_quality, first) + ear_folds(f, c, d, a, &second_quality, second);
    double first_size = sqrt(dot3(first, first)), second_size = sqrt(dot3(second, second));
    count += dot3(first, second) < FACING * first_size * second_size;
    *cost = length / (first_quality < second_quality ? first_quality : second_quality);
    return count;
}

static void emit(Filler *f, int64_t a, int64_t b, int64_t c) {
    int64_t *t = f->triangles + 3 * f->triangle_count++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
}

/* Closes the simple cycle of the `count` live positions `at` with a fan about a new point, the
   mean of its vertices: 0, or -1 on a rim when a spoke would be longer than f->longest. */
static int fan(Filler *f, const int64_t *at, Py_ssize_t count) {
    double *centre = f->added + 3 * f->added_count;
    centre[0] = centre[1] = centre[2] = 0.0;
    for (Py_ssize_t c = 0; c < count; c++)
        for (int d = 0; d < 3; d++) centre[d] += f->p[3 * f->vertex[at[c]] + d];
    for (int d = 0; d < 3; d++) centre[d] /= (double)count;
    for (Py_ssize_t c = 0; c < count; c++) {
        const double *a = f->p + 3 * f->vertex[at[c]];
        double d[3] = {a[0] - centre[0], a[1] - centre[1], a[2] - centre[2]};
        if (f->rim && !(sqrt(dot3(d, d)) <= f->longest)) return -1;
    }
    int64_t point = f->n + f->added_count++;
    for (Py_ssize_t c = 0; c < count; c++) emit(f, f->vertex[at[c]], f->vertex[at[(c + 1) % count]], point);
    return 0;
}

/* Closes the live cycle of `count` positions from `start` with a fan for each simple cycle it
   runs: where it comes back to a vertex it has left, the positions since close one (a stack of
   them, f->depth[v] where v's is on it); a cycle of two is a rung walked both ways and needs
   no triangle. 0, or -1 on a rim when a spoke would be longer than f->longest. */
static int fans(Filler *f, int64_t start, Py_ssize_t count) {
    Py_ssize_t top = 0;
    int status = 0;
    int64_t i = start;
    for (Py_ssize_t c = 0; c <= count; c++, i = f->next[i]) {   /* the last: back at the start */
        int64_t v = f->vertex[i];
        if (f->depth[v] >= 0) {
            Py_ssize_t from = f->depth[v];
            if (top - from > 2 && fan(f, f->stack + from, top - from)) status = -1;
            for (Py_ssize_t j = from; j < top; j++) f->depth[f->vertex[f->stack[j]]] = -1;
            top = from;
        }
        if (c < count) {
            f->depth[v] = top;
            f->stack[top++] = i;
        }
    }
    return status;
}

/* Whether to fill the closed walk of half-edges hs (count): when it has a rung, or when its
   vector area (written to `area`, twice, the fan's normals from its first vertex summed) faces
   as the references of its edges do (their unit vectors summed): a hole in a chart, not the
   chart. */
static int fillable(const Filler *f, const int64_t *hs, Py_ssize_t count, const int64_t *source,
                    const double *reference, double *area) {
    double beside[3] = {0.0, 0.0, 0.0};
    int rung = 0;
    area[0] = area[1] = area[2] = 0.0;
    for (Py_ssize_t i = 0; i < count; i++) {
        const double *r = reference + 3 * hs[i];
        double length = sqrt(dot3(r, r)), normal[3];
        for (int d = 0; d < 3 && length > 0; d++) beside[d] += r[d] / length;
        rung |= hs[i] >= f->rungs;
        if (i == 0 || i + 1 == count) continue;
        normal_of(f->p, source[hs[0]], source[hs[i]], source[hs[i + 1]], normal);
        for (int d = 0; d < 3; d++) area[d] += normal[d];
    }
    return rung || dot3(area, beside) > 0;
}

/* Fills the closed walk of half-edges hs (count >= 3; a vertex may come twice: a chart's corner
   touching the rest of it, a rung walked both ways): ears, then fans if it is stuck. A walk of
   the boundary's half-edges alone is filled only when its area faces as the surface beside it
   (a hole in a chart, not the chart). On a rim one that would need an edge longer than
   f->longest (a rim, not a gap) is left open: its triangles, points and edges are taken back. */
static void clip(Filler *f, const int64_t *hs, Py_ssize_t count, const int64_t *source, const double *reference) {
    for (Py_ssize_t i = 0; i < count; i++) {
        f->vertex[i] = source[hs[i]];
        memcpy(f->reference + 3 * i, reference + 3 * hs[i], 3 * sizeof(double));
        f->prev[i] = i == 0 ? count - 1 : i - 1;
        f->next[i] = i == count - 1 ? 0 : i + 1;
        f->version[i] = 0;
    }
    if (!fillable(f, hs, count, source, reference, f->area)) return;
    f->heap_size = 0;
    for (Py_ssize_t i = 0; i < count; i++) consider(f, i);
    Py_ssize_t alive = count, made = f->triangle_count, added = f->added_count, cuts = 0;
    int64_t any = 0;
    int open = 0;
    while (alive > 4 && f->heap_size > 0 && !open) {
        Ear ear = pop(f);
        int64_t i = ear.at;
        if (ear.version != f->version[i]) continue;   /* stale, or clipped */
        int64_t j = f->prev[i], k = f->next[i], u = f->vertex[j], w = f->vertex[k];
        if (has_edge(&f->edges, u, w)) {   /* added by an ear since */
            f->version[i]++;
            continue;
        }
        if (!(sqrt(distance2(f->p, u, w)) <= f->longest)) {   /* on a rim: a gap's are not considered */
            open = 1;
            break;
        }
        emit(f, u, f->vertex[i], w);
        add_edge(&f->edges, u, w);
        f->cuts[2 * cuts] = u;
        f->cuts[2 * cuts++ + 1] = w;
        normal_of(f->p, u, f->vertex[i], w, f->reference + 3 * j);
        f->version[i]++;
        f->next[j] = k;
        f->prev[k] = j;
        alive--;
        any = j;
        consider(f, j);
        consider(f, k);
    }
    if (!open && alive == 4) {   /* the last cut sees both triangles it leaves */
        int64_t a = any, b = f->next[a], c = f->next[b], d = f->next[c];
        double along, across;
        int first = quad_folds(f, a, b, c, d, &along), second = quad_folds(f, b, c, d, a, &across);
        if (second >= 0 && (first < 0 || second < first || (second == first && across < along))) {
            a = b, b = c, c = d, d = any;
            first = second;
        }
        if (first >= 0) {
            emit(f, f->vertex[a], f->vertex[b], f->vertex[c]);
            add_edge(&f->edges, f->vertex[a], f->vertex[c]);
            f->cuts[2 * cuts] = f->vertex[a];
            f->cuts[2 * cuts++ + 1] = f->vertex[c];
            f->next[a] = c;
            any = a;
            alive = 3;
        }
    }
    if (!open && alive == 3) {
        int64_t j = f->next[any], k = f->next[j];
        emit(f, f->vertex[any], f->vertex[j], f->vertex[k]);
    } else if (open || fans(f, any, alive)) {
        f->triangle_count = made;
        f->added_count = added;
        for (Py_ssize_t c = 0; c < cuts; c++) remove_edge(&f->edges, f->cuts[2 * c], f->cuts[2 * c + 1]);
    }
}

/* Fills the closed walk of half-edges walk[0..count): where it comes back to a vertex it has
   left, the half-edges since (a stack of them, f->walked[v] where v's is on it) close a cycle,
   filled apart when it is to be filled at all (``fillable``) and walks no rung both ways: a
   cycle round a chart's corner that touches the rest of it, or round a chart hanging on a
   rung (one side of a body too thin for the spacing, whose other side is at the rung's other
   end), stays in the walk, whose filling then covers the gap on both sides of the corner, or
   the band between the sides. A cycle of two is a rung walked both ways and needs no triangle. */
/* Whether the closed walk of half-edges hs (count) walks a rung both ways. */
static int walks_a_rung_twice(Filler *f, const int64_t *hs, Py_ssize_t count) {
    Py_ssize_t pairs = (f->k - f->rungs) / 2;   /* rung i runs a -> b as rungs + i, b -> a as rungs + pairs + i */
    int twice = 0;
    for (Py_ssize_t i = 0; i < count; i++)
        if (hs[i] >= f->rungs) f->crossed[hs[i] - f->rungs] = 1;
    for (Py_ssize_t i = 0; i < count; i++) {
        Py_ssize_t half = hs[i] - f->rungs;
        if (half >= 0) twice |= f->crossed[half < pairs ? half + pairs : half - pairs];
    }
    for (Py_ssize_t i = 0; i < count; i++)
        if (hs[i] >= f->rungs) f->crossed[hs[i] - f->rungs] = 0;
    return twice;
}

static void fill_walk(Filler *f, int64_t *walk, Py_ssize_t count, const int64_t *source, const double *reference) {
    Py_ssize_t top = 0;   /* walk[0..top): the stack, written over the walk as it is read */
    double area[3];
    for (Py_ssize_t i = 0; i < count; i++) {
        int64_t h = walk[i], v = source[h];
        Py_ssize_t from = f->walked[v];
        if (from >= 0 && (top - from < 3 || (fillable(f, walk + from, top - from, source, reference, area) &&
                                             !walks_a_rung_twice(f, walk + from, top - from)))) {
            if (top - from > 2) clip(f, walk + from, top - from, source, reference);
            for (Py_ssize_t j = from; j < top; j++) f->walked[source[walk[j]]] = -1;
            top = from;
        }
        f->walked[v] = top;
        walk[top++] = h;
    }
    if (top > 2) clip(f, walk, top, source, reference);
    for (Py_ssize_t j = 0; j < top; j++) f->walked[source[walk[j]]] = -1;
}

/* Fills every face (every closed walk); 0, or -1 without memory. */
static int fill_faces(Filler *f, Py_ssize_t k, const int64_t *source, const int64_t *next, const double *reference,
                      const unsigned char *rim) {
    unsigned char *done = calloc((size_t)k + 1, 1);
    int64_t *walk = malloc(((size_t)k + 1) * sizeof(int64_t));
    int status = done && walk ? 0 : -1;
    for (Py_ssize_t h0 = 0; !status && h0 < k; h0++) {
        if (done[h0]) continue;
        Py_ssize_t count = 0;
        int64_t h = h0;
        for (; h >= 0 && !done[h]; h = next[h]) {
            done[h] = 1;
            walk[count++] = h;
        }
        f->rim = rim[h0] != 0;
        if (h == h0) fill_walk(f, walk, count, source, reference);
    }
    free(done);
    free(walk);
    return status;
}

static PyObject *fill(PyObject *self, PyObject *args) {
    (void)self;
    Py_buffer points, sources, targets, nexts, references, edges, rims, triangles, added;
    Py_ssize_t rungs;
    double longest;
    if (!PyArg_ParseTuple(args, "y*y*y*y*ny*y*dy*w*w*", &points, &sources, &targets, &nexts, &rungs, &references,
                          &edges, &longest, &rims, &triangles, &added))
        return NULL;
    const Py_ssize_t word = (Py_ssize_t)sizeof(int64_t);   /* and of a double */
    Py_ssize_t n = points.len / (3 * word), k = sources.len / word, e = edges.len / (2 * word);
    const int64_t *source = sources.buf, *target = targets.buf, *next = nexts.buf, *edge = edges.buf;
    int status = 1;   /* 1: sizes, 2: an index, 3: memory */
    Filler f = {0};
    if (points.len == 3 * n * word && sources.len == k * word && targets.len == k * word && nexts.len == k * word &&
        references.len == 3 * k * word && edges.len == 2 * e * word && rims.len == k &&
        triangles.len == 3 * k * word && added.len == 3 * k * word && n < ((Py_ssize_t)1 << 31) && rungs >= 0 &&
        rungs <= k && (k - rungs) % 2 == 0) {
        status = 0;
        unsigned char *seen = calloc((size_t)k + 1, 1);
        if (!seen) status = 3;
        for (Py_ssize_t h = 0; !status && h < k; h++) {
            if (source[h] < 0 || source[h] >= n || target[h] < 0 || target[h] >= n || next[h] < -1 || next[h] >= k ||
                (next[h] >= 0 && (seen[next[h]] || source[next[h]] != target[h])))
                status = 2;
            else if (next[h] >= 0)
                seen[next[h]] = 1;
        }
        free(seen);
        for (Py_ssize_t i = 0; !status && i < 2 * e; i++)
            if (edge[i] < 0 || edge[i] >= n) status = 2;
    }
    if (!status) {
        f.p = points.buf;
        f.n = n;
        f.triangles = triangles.buf;
        f.rungs = rungs;
        f.k = k;
        f.added = added.buf;
        f.longest = longest;
        f.vertex = malloc(((size_t)k + 1) * sizeof(int64_t));
        f.prev = malloc(((size_t)k + 1) * sizeof(int64_t));
        f.next = malloc(((size_t)k + 1) * sizeof(int64_t));
        f.version = malloc(((size_t)k + 1) * sizeof(int64_t));
        f.cuts = malloc(((size_t)k + 1) * 2 * sizeof(int64_t));
        f.stack = malloc(((size_t)k + 1) * sizeof(int64_t));
        f.depth = malloc(((size_t)n + 1) * sizeof(int64_t));
        f.walked = malloc(((size_t)n + 1) * sizeof(int64_t));
        f.crossed = calloc((size_t)k + 1, 1);
        f.reference = malloc(((size_t)k + 1) * 3 * sizeof(double));
        f.heap = malloc(((size_t)k + 1) * 3 * sizeof(Ear));   /* k ears, and two more per clip */
        if (!f.vertex || !f.prev || !f.next || !f.version || !f.cuts || !f.stack || !f.depth || !f.walked ||
            !f.crossed || !f.reference || !f.heap ||
            !edge_set(&f.edges, (size_t)(e + 2 * k)))   /* the edges, the half-edges', the cuts */
            status = 3;
    }
    if (!status) {
        for (Py_ssize_t v = 0; v < n; v++) f.depth[v] = f.walked[v] = -1;
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t i = 0; i < e; i++) add_edge(&f.edges, edge[2 * i], edge[2 * i + 1]);
        for (Py_ssize_t h = 0; h < k; h++) add_edge(&f.edges, source[h], target[h]);
        if (fill_faces(&f, k, source, next, references.buf, rims.buf)) status = 3;
        Py_END_ALLOW_THREADS
    }
    free(f.edges.keys);
    free(f.vertex);
    free(f.prev);
    free(f.next);
    free(f.version);
    free(f.cuts);
    free(f.stack);
    free(f.depth);
    free(f.walked);
    free(f.crossed);
    free(f.reference);
    free(f.heap);
    PyBuffer_Release(&points);
    PyBuffer_Release(&sources);
    PyBuffer_Release(&targets);
    PyBuffer_Release(&nexts);
    PyBuffer_Release(&references);
    PyBuffer_Release(&edges);
    PyBuffer_Release(&rims);
    PyBuffer_Release(&triangles);
    PyBuffer_Release(&added);
    if (status == 1) return PyErr_Format(PyExc_ValueError, "fill: buffers whose sizes do not fit");
    if (status == 2)
        return PyErr_Format(PyExc_IndexError,
                            "fill: an index out of range, or a next given twice or not where its half-edge ends");
    if (status == 3) return PyErr_NoMemory();
    return Py_BuildValue("nn", f.triangle_count, f.added_count);
}

static PyMethodDef methods[] = {
    {"boundary", boundary, METH_VARARGS,
     "boundary(triangles, vertex_count, edges) -> count: write the edges no triangle runs the other way."},
    {"nearest", nearest, METH_VARARGS,
     "nearest(points, reach, candidate, distance): each point's nearest within reach, nearest first."},
    {"walks", walks, METH_VARARGS, "walks(next, walk) -> count: number the walks along next."},
    {"fill", fill, METH_VARARGS,
     "fill(points, source, target, next, rungs, reference, edges, longest, rim, triangles, added) -> "
     "(triangles, points): triangulate "
     "the chosen faces."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_zipper",
                                    "The zipper's loops: boundary edges, nearest boundary vertices, walks, the gap's faces filled.",
                                    -1, methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__zipper(void) { return PyModule_Create(&module); }
