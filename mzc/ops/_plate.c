/* The thin plate of densify's biharmonic method (mzc.ops.densify): its normal equations
assembled as a symmetric band, and the band's product, Cholesky factor and solve.

densify inserts n rows between the original ones and minimises the discrete thin-plate
energy over the inserted nodes with the original rows held fixed. Numbered gap by gap,
column by column, row by row, the unknowns of a gap form a band of half-width w = 2n; the
stencils centred on an original row join two gaps and are left to the caller (their share
of the diagonal and right-hand side is here). On a face that is a few hundred thousand
unknowns, a conjugate-gradient solve preconditioned by the band's exact factor. numpy's
assembly over the dense grid, LAPACK's band routines (through scipy) and importing
scipy.linalg took 3x as long as these loops, which do the same arithmetic in plain C99
(built with -ffp-contract=off: the same rounding on every CPU).

Storage, one row of w+1 doubles per unknown j (a C-ordered (size, w+1) array):
    band[j][k]   = A[j, j-k]     for k = 0..w (k = 0 the diagonal; entries with j-k < 0 unused)
    factor[j][k] = L[j, j-k]     for k = 1..w, and factor[j][0] = 1 / L[j, j]
where A = L L^T, L lower triangular with the same band. Storing the reciprocal of the
diagonal makes both solves divide-free.

Every function checks each buffer's length against the sizes it is given or implies (a
mismatch is the caller's error: ValueError) and every index before it is used; `cholesky`
returns the first unknown where A is not positive definite (-1 when it is), which the
caller turns into its one-line MzcError.
*/
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>

/* The number of rows of w+1 doubles in buffer `view` (or of doubles, when `width` is 0 and
   `vector` set), -1 with a ValueError naming `name` if its length, item size or alignment is wrong. */
static Py_ssize_t rows_of(const Py_buffer *view, Py_ssize_t width, const char *name)
{
    Py_ssize_t row = (width + 1) * (Py_ssize_t)sizeof(double);
    if (view->len % row || view->itemsize != (Py_ssize_t)sizeof(double) || (uintptr_t)view->buf % sizeof(double)) {
        PyErr_Format(PyExc_ValueError, "%s: %zd bytes are not whole rows of %zd aligned doubles",
                     name, view->len, width + 1);
        return -1;
    }
    return view->len / row;
}

/* The half-width from the Python argument, checked: 0 .. 2^20. */
static int check_width(Py_ssize_t width)
{
    if (width < 0 || width > (1 << 20)) {
        PyErr_Format(PyExc_ValueError, "band half-width %zd is outside 0..2^20", width);
        return -1;
    }
    return 0;
}

/* True when no row of j..j+w-1 of band `a` (size rows) reaches before row j: the rows before j
   and the rows from j on are two systems (a band matrix's factor keeps its zeros). */
static int splits_at(const double *a, Py_ssize_t size, Py_ssize_t w, Py_ssize_t j)
{
    for (Py_ssize_t m = 0; m < w && j + m < size; m++)
        for (Py_ssize_t k = m + 1; k <= w; k++)
            if (a[(j + m) * (w + 1) + k] != 0.0)
                return 0;
    return 1;
}

/* The first row from the middle on where band `a` splits into two systems (splits_at), or size.
   The two are solved side by side: each row's arithmetic waits on the row before (about 12
   cycles a row), and two independent chains fill those waits. */
static Py_ssize_t middle_split(const double *a, Py_ssize_t size, Py_ssize_t w)
{
    for (Py_ssize_t j = size / 2; j < size; j++)
        if (splits_at(a, size, w, j))
            return j;
    return size;
}

/* Row j of the factor of the system whose first row is `first` (entries before it are zero):
   L[j, i] = (A[j, i] - sum over m < i of L[j, m] L[i, m]) / L[i, i], then the diagonal.
   0, or -1 when the pivot is not positive. */
static int factor_row(double *a, Py_ssize_t w, Py_ssize_t j, Py_ssize_t first)
{
    Py_ssize_t stride = w + 1, top = j - first < w ? j - first : w;
    double *row = a + j * stride;
    for (Py_ssize_t k = top; k >= 1; k--) {
        const double *other = a + (j - k) * stride;         /* row i = j - k */
        double s = row[k];
        for (Py_ssize_t m = top; m > k; m--)                 /* L[j, j-m] L[i, j-m], j-m < i */
            s -= row[m] * other[m - k];
        row[k] = s * other[0];
    }
    double d = row[0];
    for (Py_ssize_t k = top; k >= 1; k--)
        d -= row[k] * row[k];
    if (!(d > 0.0))
        return -1;
    row[0] = 1.0 / sqrt(d);
    return 0;
}

/* In place: band (size rows) -> its factor, the rows before and after the middle split side
   by side. Returns -1, or the first row found whose pivot is not positive. */
static Py_ssize_t factor_rows(double *a, Py_ssize_t size, Py_ssize_t w)
{
    Py_ssize_t split = middle_split(a, size, w), rest = size - split;
    for (Py_ssize_t i = 0; i < split || i < rest; i++) {
        if (i < split && factor_row(a, w, i, 0))
            return i;
        if (i < rest && factor_row(a, w, split + i, split))
            return split + i;
    }
    return -1;
}

/* Forward substitution of row j (L y = x, the system's first row `first`). */
static inline void forward_row(const double *l, Py_ssize_t w, double *x, Py_ssize_t j, Py_ssize_t first)
{
    const double *row = l + j * (w + 1);
    Py_ssize_t top = j - first < w ? j - first : w;
    double s = x[j];
    for (Py_ssize_t k = top; k >= 1; k--)                    /* the newest value last */
        s -= row[k] * x[j - k];
    x[j] = s * row[0];
}

/* Back substitution of row j (L^T x = y): x[j], then its share taken from the rows before. */
static inline void backward_row(const double *l, Py_ssize_t w, double *x, Py_ssize_t j, Py_ssize_t first)
{
    const double *row = l + j * (w + 1);
    Py_ssize_t top = j - first < w ? j - first : w;
    double v = x[j] * row[0];
    x[j] = v;
    for (Py_ssize_t k = 1; k <= top; k++)
        x[j - k] -= row[k] * v;
}

/* In place: x (size) -> A^-1 x from the factor, both halves of the middle split side by side. */
static void solve_rows(const double *l, Py_ssize_t size, Py_ssize_t w, double *x)
{
    Py_ssize_t split = middle_split(l, size, w), rest = size - split;
    for (Py_ssize_t i = 0; i < split || i < rest; i++) {
        if (i < split)
            forward_row(l, w, x, i, 0);
        if (i < rest)
            forward_row(l, w, x, split + i, split);
    }
    for (Py_ssize_t i = 0; i < split || i < rest; i++) {
        if (i < split)
            backward_row(l, w, x, split - 1 - i, 0);
        if (i < rest)
            backward_row(l, w, x, size - 1 - i, split);
    }
}

/* out (size) = A x for the symmetric A whose lower band is `a`. */
static void product_rows(const double *a, Py_ssize_t size, Py_ssize_t w, const double *x, double *out)
{
    Py_ssize_t stride = w + 1;
    for (Py_ssize_t j = 0; j < size; j++)
        out[j] = 0.0;
    for (Py_ssize_t j = 0; j < size; j++) {
        const double *row = a + j * stride;
        Py_ssize_t top = j < w ? j : w;
        double s = row[0] * x[j];
        for (Py_ssize_t k = 1; k <= top; k++) {
            s += row[k] * x[j - k];
            out[j - k] += row[k] * x[j];
        }
        out[j] += s;
    }
}

/* One node of a stencil: unknown `index`, or a known `value` (index -1); its coefficient `a`. */
typedef struct {
    Py_ssize_t index;
    double value, a;
} Node;

/* Add the term weight (sum a_i u_i)^2 of one stencil to the normal equations: weight a_i a_j to
   A at each pair of its unknowns (the later one's row), -weight a_i (sum over known nodes of
   a_j value_j) to b. -1 if two of its unknowns are more than w apart (a numbering error). */
static int add_stencil(double *band, double *rhs, Py_ssize_t w, const Node *nodes, int count, double weight)
{
    double known = 0.0;
    for (int i = 0; i < count; i++)
        if (nodes[i].index < 0)
            known += nodes[i].a * nodes[i].value;
    for (int i = 0; i < count; i++) {
        Py_ssize_t p = nodes[i].index;
        if (p < 0)
            continue;
        rhs[p] -= weight * nodes[i].a * known;
        for (int j = 0; j < count; j++) {
            Py_ssize_t q = nodes[j].index;
            if (q < 0 || q > p)
                continue;
            if (p - q > w)
                return -1;
            band[p * (w + 1) + (p - q)] += weight * nodes[i].a * nodes[j].a;
        }
    }
    return 0;
}

/* The node of gap g's stacked row r at column c: r = 0 and r = n+1 are the gap's original
   rows (known values of z), 1..n its inserted rows (unknowns first[g][c] + r - 1). */
static Node stacked(const double *z, const int64_t *first, Py_ssize_t cols, Py_ssize_t n, Py_ssize_t g,
                    Py_ssize_t c, Py_ssize_t r, double a)
{
    Node node = {-1, 0.0, a};
    if (r == 0 || r == n + 1)
        node.value = z[(g + (r > 0)) * cols + c];
    else
        node.index = (Py_ssize_t)first[g * cols + c] + r - 1;
    return node;
}

/* Assemble the band and b of the plate over gaps x cols (see mzc.ops.densify.plate_equations):
   z the original rows, first[g][c] the first unknown of gap g's column c (-1 outside the
   domain), joined_rows and joined_gaps (uint8) 1 where the edge from column c to c+1 of an
   original row, of a gap's inserted rows, may be crossed. */
static int assemble(const double *z, const int64_t *first, const uint8_t *joined_rows, const uint8_t *joined_gaps,
                    Py_ssize_t gaps, Py_ssize_t cols, Py_ssize_t n, const double *weights, double *band,
                    double *rhs, Py_ssize_t size)
{
    Py_ssize_t w = 2 * n;
    double along = weights[0], across = weights[1], twist = weights[2];
    for (Py_ssize_t j = 0; j < size * (w + 1); j++)
        band[j] = 0.0;
    for (Py_ssize_t j = 0; j < size; j++)
        rhs[j] = 0.0;
    for (Py_ssize_t g = 0; g < gaps; g++)
        for (Py_ssize_t c = 0; c < cols; c++) {
            if (first[g * cols + c] < 0)
                continue;
            int left = c > 0 && first[g * cols + c - 1] >= 0 && joined_gaps[g * (cols - 1) + c - 1];
            int right = c + 1 < cols && first[g * cols + c + 1] >= 0 && joined_gaps[g * (cols - 1) + c];
            int err = 0;
            for (Py_ssize_t r = 1; r <= n; r++) {           /* across the rows, centred on an inserted row */
                Node nodes[3] = {stacked(z, first, cols, n, g, c, r - 1, 1.0), stacked(z, first, cols, n, g, c, r, -2.0),
                                 stacked(z, first, cols, n, g, c, r + 1, 1.0)};
                err |= add_stencil(band, rhs, w, nodes, 3, across);
            }
            if (g + 1 < gaps && first[(g + 1) * cols + c] >= 0) {
                /* across, centred on original row g+1: each side's share; the pair is the caller's */
                Node above[2] = {stacked(z, first, cols, n, g, c, n, 1.0), stacked(z, first, cols, n, g, c, n + 1, -2.0)};
                Node below[2] = {stacked(z, first, cols, n, g + 1, c, 1, 1.0),
                                 stacked(z, first, cols, n, g, c, n + 1, -2.0)};
                err |= add_stencil(band, rhs, w, above, 2, across);
                err |= add_stencil(band, rhs, w, below, 2, across);
            }
            for (Py_ssize_t r = 1; r <= n && left && right; r++) {   /* along the rows, centred at c */
                Node nodes[3] = {stacked(z, first, cols, n, g, c - 1, r, 1.0), stacked(z, first, cols, n, g, c, r, -2.0),
                                 stacked(z, first, cols, n, g, c + 1, r, 1.0)};
                err |= add_stencil(band, rhs, w, nodes, 3, along);
            }
            for (Py_ssize_t r = 0; r <= n && right; r++) {  /* the twist of the cell right of c, rows r, r+1 */
                if ((r == 0 && !joined_rows[g * (cols - 1) + c]) || (r == n && !joined_rows[(g + 1) * (cols - 1) + c]))
                    continue;
                Node nodes[4] = {stacked(z, first, cols, n, g, c, r, 1.0), stacked(z, first, cols, n, g, c + 1, r, -1.0),
                                 stacked(z, first, cols, n, g, c, r + 1, -1.0),
                                 stacked(z, first, cols, n, g, c + 1, r + 1, 1.0)};
                err |= add_stencil(band, rhs, w, nodes, 4, twist);
            }
            if (err)
                return -1;
        }
    return 0;
}

/* Check that buffer `view` holds `count` items of `size` bytes, aligned for them; -1 with a
   ValueError naming `name` if not. */
static int check_items(const Py_buffer *view, Py_ssize_t count, Py_ssize_t size, const char *name)
{
    if (view->itemsize != size || count < 0 || count > PY_SSIZE_T_MAX / size || view->len != count * size
        || (uintptr_t)view->buf % (uintptr_t)size) {
        PyErr_Format(PyExc_ValueError, "%s: %zd bytes of %zd-byte items, expected %zd aligned items of %zd bytes",
                     name, view->len, view->itemsize, count, size);
        return -1;
    }
    return 0;
}

static PyObject *plate(PyObject *self, PyObject *args)
{
    Py_buffer z, first, joined_rows, joined_gaps, band, rhs;
    Py_ssize_t gaps, cols, n, size = 0;
    double weights[3];
    int failed = 0;
    if (!PyArg_ParseTuple(args, "y*y*y*y*nnn(ddd)w*w*", &z, &first, &joined_rows, &joined_gaps, &gaps, &cols, &n,
                          &weights[0], &weights[1], &weights[2], &band, &rhs))
        return NULL;
    if (gaps < 1 || cols < 1 || n < 1 || n > (1 << 20) || gaps > PY_SSIZE_T_MAX / cols / (n + 2))
        PyErr_Format(PyExc_ValueError, "%zd gaps x %zd columns x %zd rows is not a plate", gaps, cols, n);
    else if (check_items(&z, (gaps + 1) * cols, 8, "z") == 0 && check_items(&first, gaps * cols, 8, "first") == 0
             && check_items(&joined_rows, (gaps + 1) * (cols - 1), 1, "joined_rows") == 0
             && check_items(&joined_gaps, gaps * (cols - 1), 1, "joined_gaps") == 0
             && (size = rows_of(&band, 2 * n, "band")) >= 0 && check_items(&rhs, size, 8, "rhs") == 0) {
        const int64_t *start = first.buf;
        for (Py_ssize_t i = 0; i < gaps * cols; i++)
            if (start[i] < -1 || start[i] > size - n) {
                PyErr_Format(PyExc_ValueError, "first: unknown %lld of %zd is out of range", (long long)start[i], size);
                break;
            }
        if (!PyErr_Occurred()) {
            Py_BEGIN_ALLOW_THREADS
            failed = assemble(z.buf, first.buf, joined_rows.buf, joined_gaps.buf, gaps, cols, n, weights, band.buf,
                              rhs.buf, size);
            Py_END_ALLOW_THREADS
            if (failed)
                PyErr_SetString(PyExc_ValueError, "first: two unknowns of one stencil are more than 2n apart");
        }
    }
    PyBuffer_Release(&z);
    PyBuffer_Release(&first);
    PyBuffer_Release(&joined_rows);
    PyBuffer_Release(&joined_gaps);
    PyBuffer_Release(&band);
    PyBuffer_Release(&rhs);
    return PyErr_Occurred() ? NULL : Py_NewRef(Py_None);
}

static PyObject *cholesky(PyObject *self, PyObject *args)
{
    Py_buffer band;
    Py_ssize_t width, size, failed = -1;
    if (!PyArg_ParseTuple(args, "w*n", &band, &width))
        return NULL;
    if (check_width(width) == 0 && (size = rows_of(&band, width, "band")) >= 0) {
        Py_BEGIN_ALLOW_THREADS
        failed = factor_rows(band.buf, size, width);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&band);
    return PyErr_Occurred() ? NULL : PyLong_FromSsize_t(failed);
}

static PyObject *solve(PyObject *self, PyObject *args)
{
    Py_buffer factor, x;
    Py_ssize_t width, size;
    if (!PyArg_ParseTuple(args, "y*nw*", &factor, &width, &x))
        return NULL;
    if (check_width(width) == 0 && (size = rows_of(&factor, width, "factor")) >= 0) {
        if (rows_of(&x, 0, "vector") != size)
            PyErr_Format(PyExc_ValueError, "vector: %zd bytes for %zd unknowns", x.len, size);
        else {
            Py_BEGIN_ALLOW_THREADS
            solve_rows(factor.buf, size, width, x.buf);
            Py_END_ALLOW_THREADS
        }
    }
    PyBuffer_Release(&factor);
    PyBuffer_Release(&x);
    return PyErr_Occurred() ? NULL : Py_NewRef(Py_None);
}

static PyObject *product(PyObject *self, PyObject *args)
{
    Py_buffer band, x, out;
    Py_ssize_t width, size;
    if (!PyArg_ParseTuple(args, "y*ny*w*", &band, &width, &x, &out))
        return NULL;
    if (check_width(width) == 0 && (size = rows_of(&band, width, "band")) >= 0) {
        if (rows_of(&x, 0, "vector") != size || rows_of(&out, 0, "out") != size)
            PyErr_Format(PyExc_ValueError, "vector and out must hold %zd doubles each", size);
        else if (x.buf == out.buf)
            PyErr_SetString(PyExc_ValueError, "vector and out must be different arrays");
        else {
            Py_BEGIN_ALLOW_THREADS
            product_rows(band.buf, size, width, x.buf, out.buf);
            Py_END_ALLOW_THREADS
        }
    }
    PyBuffer_Release(&band);
    PyBuffer_Release(&x);
    PyBuffer_Release(&out);
    return PyErr_Occurred() ? NULL : Py_NewRef(Py_None);
}

static PyMethodDef methods[] = {
    {"plate", plate, METH_VARARGS,
     "plate(z, first, joined_rows, joined_gaps, gaps, cols, n, (along, across, twist), band, rhs): "
     "assemble the band and right-hand side in place."},
    {"cholesky", cholesky, METH_VARARGS,
     "cholesky(band, width): factor the band in place; -1, or the first row that is not positive definite."},
    {"solve", solve, METH_VARARGS, "solve(factor, width, x): x = A^-1 x in place."},
    {"product", product, METH_VARARGS, "product(band, width, x, out): out = A x."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "mzc.ops._plate", "The thin plate of densify: assembly, band product, Cholesky factor and solve.", -1,
    methods,
};

PyMODINIT_FUNC PyInit__plate(void)
{
    return PyModule_Create(&module);
}
