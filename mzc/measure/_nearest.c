/* The exact distance from points to a triangle mesh, and a nearest triangle: a bounding
 * volume hierarchy over the triangles and a closest-first search per point
 * (mzc/measure/metrics.py, nearest_triangles).
 *
 * nearest(points, triangles, samples, distances, nearest) -> status
 *   points     float64 (n, 3): the mesh's vertices
 *   triangles  int64 (m, 3): corner indices into points, each checked to be in 0..n-1
 *   samples    float64 (k, 3)
 *   distances  float64 (k): written with each sample's distance to the mesh
 *   nearest    int64 (k): written with the index of a triangle at that distance (-1 if m = 0)
 * The buffers are C-contiguous (the y* and w* formats) and their sizes are checked against
 * each other before anything is read. Returns 0, or NEAREST_BAD_SIZE (sizes that do not
 * fit), NEAREST_BAD_INDEX (a corner index out of range), NEAREST_NO_MEMORY or
 * NEAREST_TOO_MANY (more than MAX_TRIANGLES or MAX_POINTS), which metrics.py turns into
 * errors. An empty mesh is infinitely far from every sample.
 *
 * The tree: the triangles sorted by the Morton code of their box centres (63 bits, 21 per
 * axis, over the box of the points; a radix sort), then split top-down where the codes of a
 * range first differ in their highest differing bit (binary search), or in the middle when
 * they are all equal, down to leaves of at most LEAF_SIZE triangles. Each split by a bit
 * lengthens the common prefix of both halves, so a path has at most 63 of them, then at
 * most log2(MAX_TRIANGLES) = 30 halvings: the depth stays under 95, which bounds the
 * search's stack (MAX_DEPTH). Boxes are floats: a mesh whose coordinates reach past
 * FLOAT_REACH (2^100) has them stored scaled by a power of two (exactly, so still rounded
 * outwards), the box distances scaled back; in float's range they would be infinite, every
 * box as near as the next, and the search would measure every triangle for every sample
 * (a mesh at heights of 1e99: 30 s for one diff of 2 million triangles, unfinished).
 * Nodes are stored depth first, a node's left child right after
 * it; a node's box is the union of its children's, a leaf's that of its corners, in float
 * rounded outwards. A leaf holds a range of the leaf order, in which the triangles' vertex
 * indices are copied (int32): the tree takes about 50 bytes a triangle, the search 32 a
 * sample (copying the corners themselves was no faster and took 60 bytes a triangle more;
 * reaching the vertices through the sorted order's triangle indices was 15% slower).
 *
 * The search: the samples in the Morton order of their own codes, so that consecutive
 * searches walk the same part of the tree, each starting from the bound of the triangle
 * nearest to the sample before. A search keeps the best squared distance so far, visits
 * the nearer child first and skips a node whose box is farther than that best (raised by a
 * billionth, the slack for the rounding of the box distance). That slack would make a search
 * measure every triangle when a sample is a billion times farther from the mesh than the
 * mesh is deep (a flat mesh 1e10 above a unit one: every triangle within a billionth), so
 * once a search has measured BUDGET triangles it skips the boxes no nearer than its best
 * (without slack): a search that long has its answer to round-off. Each triangle is measured by
 * the point-triangle formula (triangle_distance2) whose numpy form tests/test_mesh_distance.py
 * keeps as its reference: the same operations in the same order, -ffp-contract=off keeping
 * them unfused, give the same bits. The GIL is released while it runs, on one thread.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define NEAREST_BAD_SIZE 1
#define NEAREST_BAD_INDEX 2
#define NEAREST_NO_MEMORY 3
#define NEAREST_TOO_MANY 4

#define LEAF_SIZE 4
#define MAX_TRIANGLES (INT32_MAX / 2) /* so that the 2m - 1 nodes are counted in int32 */
#define MAX_POINTS INT32_MAX           /* vertex indices in int32 */
#define MAX_DEPTH 128 /* above the depth of any tree, under 95 */
#define FLOAT_REACH 100 /* boxes of coordinates up to 2^100 are stored as they are, well inside float's 2^128 */
/* (1 + 1e-9)^2: a box within a billionth of the best distance is still searched */
#define WIDEN2 (1.0 + 2e-9 + 1e-18)
/* triangles a search measures with that slack: searches of real meshes measure tens to hundreds
 * (f18 against its rebuild at most 134, two unrelated objects of shared/data at most 633) */
#define BUDGET 1024

typedef struct {
    float lo[3], hi[3]; /* the box, rounded outwards */
    int32_t first;      /* leaf: its first triangle in leaf order; inner node: its right child */
    int32_t count;      /* leaf: its triangle count (> 0); inner node: 0 */
} Node;

typedef struct {
    uint64_t code; /* a Morton code */
    int64_t index; /* of the triangle or sample */
} Key;

/* the triangles' sort runs through the room of the 2m nodes (C99's static assertion) */
typedef char nodes_hold_the_keys[2 * sizeof(Node) >= sizeof(Key) ? 1 : -1];

typedef struct {
    const double *points;
    const int32_t *vertices; /* the vertex indices of each triangle, 3 a triangle, in leaf order */
    Node *nodes;
    int64_t used;  /* nodes, while they are being made */
    double shrink; /* boxes hold coordinates times this power of two (1 within FLOAT_REACH) */
    double grow2;  /* 1 / shrink^2: box distances back to the coordinates' scale */
} Tree;

static double dot(const double u[3], const double v[3]) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; }

static void cross(const double u[3], const double v[3], double out[3]) {
    out[0] = u[1] * v[2] - u[2] * v[1];
    out[1] = u[2] * v[0] - u[0] * v[2];
    out[2] = u[0] * v[1] - u[1] * v[0];
}

static void minus(const double u[3], const double v[3], double out[3]) {
    out[0] = u[0] - v[0];
    out[1] = u[1] - v[1];
    out[2] = u[2] - v[2];
}

/* numpy's minimum: NaN if either is NaN */
static double smaller(double x, double y) { return (x < y || isnan(x)) ? x : y; }

/* Squared distance from a point to the segment start + t edge, t in [0, 1], given
 * offset = p - start; a zero-length segment is its point. */
static double segment_distance2(const double offset[3], const double edge[3]) {
    double length2 = dot(edge, edge), t = 0.0, rest[3];
    if (length2 > 0) {
        t = dot(offset, edge) / length2;
        if (t < 0) t = 0.0; /* np.clip(t, 0, 1), which keeps a NaN */
        if (t > 1) t = 1.0;
    }
    for (int i = 0; i < 3; i++) rest[i] = offset[i] - t * edge[i];
    return dot(rest, rest);
}

/* Squared distance from p to the triangle of corners c[0..8]: to its plane when p projects
 * inside its three edges, else to the nearest edge; a zero-area triangle is only its edges. */
static double triangle_distance2(const double p[3], const double *c) {
    const double *a = c, *b = c + 3, *cc = c + 6;
    double ab[3], bc[3], ca[3], ap[3], bp[3], cp[3], ac[3], normal[3], side[3];
    minus(b, a, ab);
    minus(cc, b, bc);
    minus(a, cc, ca);
    minus(p, a, ap);
    minus(p, b, bp);
    minus(p, cc, cp);
    for (int i = 0; i < 3; i++) ac[i] = -ca[i];
    cross(ab, ac, normal);
    double norm2 = dot(normal, normal);
    int inside = norm2 > 0;
    cross(ab, ap, side);
    inside &= dot(side, normal) >= 0;
    cross(bc, bp, side);
    inside &= dot(side, normal) >= 0;
    cross(ca, cp, side);
    inside &= dot(side, normal) >= 0;
    if (inside) {
        double height = dot(ap, normal);
        return height * height / norm2;
    }
    return smaller(smaller(segment_distance2(ap, ab), segment_distance2(bp, bc)), segment_distance2(cp, ca));
}

/* Squared distance from p to a node's box (0 inside it). */
static double box_distance2(const double p[3], const Node *node, const Tree *tree) {
    double sum = 0.0;
    for (int i = 0; i < 3; i++) {
        double x = p[i] * tree->shrink, below = node->lo[i] - x, above = x - node->hi[i];
        double gap = below > above ? below : above;
        if (gap > 0) sum += gap * gap;
    }
    return sum * tree->grow2;
}

/* The float nearest to x on the side of -inf (``down``) or +inf: a box rounded outwards. */
static float outwards(double x, int down) {
    float f = (float)x;
    if (down ? (double)f > x : (double)f < x) f = nextafterf(f, down ? -INFINITY : INFINITY);
    return f;
}

/* The 9 coordinates of the triangle at ``place`` in leaf order. */
static void corners_of(const Tree *tree, int64_t place, double corners[9]) {
    const int32_t *vertex = tree->vertices + 3 * place;
    for (int corner = 0; corner < 3; corner++)
        memcpy(corners + 3 * corner, tree->points + 3 * (int64_t)vertex[corner], 3 * sizeof(double));
}

/* A leaf of order[lo..hi): the box of their corners. */
static void make_leaf(const Tree *tree, Node *node, int64_t lo, int64_t hi) {
    double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY}, corners[9];
    for (int64_t place = lo; place < hi; place++) {
        corners_of(tree, place, corners);
        for (int corner = 0; corner < 3; corner++) {
            const double *point = corners + 3 * corner;
            for (int i = 0; i < 3; i++) {
                low[i] = point[i] < low[i] ? point[i] : low[i];
                high[i] = point[i] > high[i] ? point[i] : high[i];
            }
        }
    }
    for (int i = 0; i < 3; i++) {
        node->lo[i] = outwards(low[i] * tree->shrink, 1);
        node->hi[i] = outwards(high[i] * tree->shrink, 0);
    }
    node->first = (int32_t)lo;
    node->count = (int32_t)(hi - lo);
}

/* The highest set bit of x. */
static uint64_t highest_bit(uint64_t x) {
    for (int shift = 1; shift < 64; shift <<= 1) x |= x >> shift;
    return x ^ (x >> 1);
}

/* Where to split keys[lo..hi) (Morton order, at least two keys): at the first key with the
 * highest bit in which the codes differ, else (all equal) in the middle. */
static int64_t split(const Key *keys, int64_t lo, int64_t hi) {
    uint64_t differ = keys[lo].code ^ keys[hi - 1].code;
    if (!differ) return lo + (hi - lo) / 2;
    uint64_t bit = highest_bit(differ);
    int64_t lacks = lo, has = hi - 1; /* the codes share the bits above ``bit``, so they are sorted by it */
    while (has - lacks > 1) {
        int64_t mid = lacks + (has - lacks) / 2;
        if (keys[mid].code & bit) has = mid;
        else lacks = mid;
    }
    return has;
}

/* Build the subtree of order[lo..hi) at the next free node; returns its index. */
static int64_t build_node(Tree *tree, const Key *order, int64_t lo, int64_t hi) {
    int64_t index = tree->used++;
    if (hi - lo <= LEAF_SIZE) {
        make_leaf(tree, &tree->nodes[index], lo, hi);
        return index;
    }
    int64_t mid = split(order, lo, hi);
    int64_t left = build_node(tree, order, lo, mid), right = build_node(tree, order, mid, hi);
    Node *node = &tree->nodes[index], *a = &tree->nodes[left], *b = &tree->nodes[right];
    for (int i = 0; i < 3; i++) {
        node->lo[i] = a->lo[i] < b->lo[i] ? a->lo[i] : b->lo[i];
        node->hi[i] = a->hi[i] > b->hi[i] ? a->hi[i] : b->hi[i];
    }
    node->first = (int32_t)right;
    node->count = 0;
    return index;
}

/* The squared distance from p to the nearest triangle, starting from the bound of the one
 * at place *which in leaf order; *which becomes the nearest one's place. */
static double nearest2(const double p[3], const Tree *tree, int64_t *which) {
    const Node *nodes = tree->nodes;
    int64_t stack[MAX_DEPTH];
    double reach[MAX_DEPTH], corners[9];
    int top = 0;
    int64_t measured = 0;
    corners_of(tree, *which, corners);
    double best = triangle_distance2(p, corners);
    stack[top] = 0;
    reach[top++] = box_distance2(p, &nodes[0], tree);
    while (top) {
        top--;
        if (reach[top] > best * WIDEN2 || (measured > BUDGET && reach[top] >= best)) continue;
        const Node *node = &nodes[stack[top]];
        if (node->count) {
            measured += node->count;
            for (int64_t t = node->first; t < node->first + node->count; t++) {
                corners_of(tree, t, corners);
                double distance2 = triangle_distance2(p, corners);
                if (distance2 < best || (isnan(distance2) && !isnan(best))) {
                    best = distance2;
                    *which = t;
                }
            }
            continue;
        }
        int64_t near = stack[top] + 1, far = node->first;
        double near_reach = box_distance2(p, &nodes[near], tree), far_reach = box_distance2(p, &nodes[far], tree);
        if (far_reach < near_reach) {
            int64_t swap = near;
            double swap_reach = near_reach;
            near = far, near_reach = far_reach;
            far = swap, far_reach = swap_reach;
        }
        stack[top] = far;
        reach[top++] = far_reach;
        stack[top] = near;
        reach[top++] = near_reach;
    }
    return best;
}

/* 21 bits of x spread out to every third bit. */
static uint64_t spread(uint64_t x) {
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffu;
    x = (x | x << 16) & 0x1f0000ff0000ffu;
    x = (x | x << 8) & 0x100f00f00f00f00fu;
    x = (x | x << 4) & 0x10c30c30c30c30c3u;
    x = (x | x << 2) & 0x1249249249249249u;
    return x;
}

/* The Morton code of p on a 2^21 lattice over the box [lo, hi] (outside it, clamped). */
static uint64_t morton(const double p[3], const double lo[3], const double hi[3]) {
    uint64_t code = 0;
    for (int i = 0; i < 3; i++) {
        double size = hi[i] - lo[i], unit = size > 0 ? (p[i] - lo[i]) / size : 0.0;
        unit = unit > 0 ? (unit < 1 ? unit : 1.0) : 0.0; /* a NaN goes to 0 */
        code |= spread((uint64_t)(unit * 2097151.0)) << i;
    }
    return code;
}

/* Sort keys by code, equal codes in their order: a radix sort, a byte at a time, through
 * ``scratch``, room for as many keys. */
static void sort_keys(Key *keys, int64_t count, Key *scratch) {
    int64_t histogram[8][256] = {{0}};
    Key *from = keys, *to = scratch;
    for (int64_t k = 0; k < count; k++)
        for (int byte = 0; byte < 8; byte++) histogram[byte][(keys[k].code >> (8 * byte)) & 255]++;
    for (int byte = 0; byte < 8; byte++) {
        int64_t *offset = histogram[byte], total = 0;
        if (count == 0 || offset[(keys[0].code >> (8 * byte)) & 255] == count) continue; /* one value */
        for (int digit = 0; digit < 256; digit++) {
            int64_t size = offset[digit];
            offset[digit] = total;
            total += size;
        }
        for (int64_t k = 0; k < count; k++) to[offset[(from[k].code >> (8 * byte)) & 255]++] = from[k];
        Key *swap = from;
        from = to;
        to = swap;
    }
    if (from != keys) memcpy(keys, from, (size_t)count * sizeof(Key));
}

/* The whole job on checked sizes: build, search every sample, free. */
static int measure(const double *points, int64_t n, const int64_t *triangles, int64_t m, const double *samples,
                   int64_t k, double *distances, int64_t *nearest) {
    for (int64_t i = 0; i < 3 * m; i++)
        if (triangles[i] < 0 || triangles[i] >= n) return NEAREST_BAD_INDEX;
    if (m == 0) {
        for (int64_t s = 0; s < k; s++) {
            distances[s] = INFINITY;
            nearest[s] = -1;
        }
        return 0;
    }
    /* the samples' keys, then as many for their sort; the nodes' room serves the triangles' sort */
    Key *order = malloc((size_t)m * sizeof(Key)), *queue = malloc((size_t)(k ? 2 * k : 1) * sizeof(Key));
    Node *nodes = malloc((size_t)(2 * m) * sizeof(Node)); /* a binary tree of at most m leaves */
    int32_t *vertices = malloc((size_t)m * 3 * sizeof(int32_t));
    int status = NEAREST_NO_MEMORY;
    if (!order || !queue || !nodes || !vertices) goto done;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t v = 0; v < n; v++)
        for (int i = 0; i < 3; i++) {
            lo[i] = points[3 * v + i] < lo[i] ? points[3 * v + i] : lo[i];
            hi[i] = points[3 * v + i] > hi[i] ? points[3 * v + i] : hi[i];
        }
    for (int64_t t = 0; t < m; t++) {
        double centre[3];
        for (int i = 0; i < 3; i++) {
            double x = points[3 * triangles[3 * t] + i], y = points[3 * triangles[3 * t + 1] + i];
            double z = points[3 * triangles[3 * t + 2] + i];
            double low = x < y ? x : y, high = x > y ? x : y;
            low = z < low ? z : low;
            high = z > high ? z : high;
            centre[i] = 0.5 * low + 0.5 * high;
        }
        order[t].code = morton(centre, lo, hi);
        order[t].index = t;
    }
    for (int64_t s = 0; s < k; s++) {
        queue[s].code = morton(samples + 3 * s, lo, hi);
        queue[s].index = s;
    }
    sort_keys(order, m, (Key *)nodes); /* 2m nodes of 32 bytes hold m keys of 16 */
    sort_keys(queue, k, queue + k);
    for (int64_t t = 0; t < m; t++)
        for (int corner = 0; corner < 3; corner++)
            vertices[3 * t + corner] = (int32_t)triangles[3 * order[t].index + corner];
    Tree tree = {points, vertices, nodes, 0, 1.0, 1.0};
    int exponent = 0;
    for (int i = 0; i < 3; i++) {
        int e;
        frexp(fmax(fabs(lo[i]), fabs(hi[i])), &e);
        exponent = e > exponent ? e : exponent;
    }
    if (exponent > FLOAT_REACH) {
        tree.shrink = ldexp(1.0, FLOAT_REACH - exponent);
        tree.grow2 = ldexp(1.0, 2 * (exponent - FLOAT_REACH));
    }
    build_node(&tree, order, 0, m);
    int64_t which = 0;
    for (int64_t s = 0; s < k; s++) {
        int64_t sample = queue[s].index;
        distances[sample] = sqrt(nearest2(samples + 3 * sample, &tree, &which));
        nearest[sample] = order[which].index;
    }
    status = 0;
done:
    free(order);
    free(queue);
    free(nodes);
    free(vertices);
    return status;
}

static PyObject *nearest(PyObject *self, PyObject *args) {
    (void)self;
    Py_buffer points, triangles, samples, distances, found;
    if (!PyArg_ParseTuple(args, "y*y*y*w*w*", &points, &triangles, &samples, &distances, &found)) return NULL;
    const Py_ssize_t row = 3 * (Py_ssize_t)sizeof(double); /* int64 rows are as long */
    Py_ssize_t n = points.len / row, m = triangles.len / row, k = samples.len / row;
    int status = NEAREST_BAD_SIZE;
    if (m > MAX_TRIANGLES || n > MAX_POINTS) status = NEAREST_TOO_MANY;
    else if (points.len % row == 0 && triangles.len % row == 0 && samples.len % row == 0 &&
             distances.len == k * (Py_ssize_t)sizeof(double) && found.len == k * (Py_ssize_t)sizeof(int64_t)) {
        Py_BEGIN_ALLOW_THREADS
        status = measure(points.buf, n, triangles.buf, m, samples.buf, k, distances.buf, found.buf);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&points);
    PyBuffer_Release(&triangles);
    PyBuffer_Release(&samples);
    PyBuffer_Release(&distances);
    PyBuffer_Release(&found);
    return PyLong_FromLong(status);
}

static PyMethodDef methods[] = {
    {"nearest", nearest, METH_VARARGS,
     "nearest(points, triangles, samples, distances, nearest) -> status: each sample's exact distance to the mesh "
     "and a nearest triangle, written into the last two."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_nearest",
                                    "The exact distance from points to a triangle mesh (a bounding volume hierarchy).",
                                    -1, methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__nearest(void) { return PyModule_Create(&module); }
