/* Depth jumps of a grid's edges (mzc.ops.triangulation.jumps_between).

   An edge between two grid-frame node points is a jump when it lies within a small angle of
   the node line through its midpoint: |e . l| > cos(angle) |e|, e the edge, l the line's
   unit direction (+z on planar grids, from the axis on cylindrical ones, from the centre on
   spherical ones; 0 where the midpoint is on the axis or at the centre). The arithmetic is
   that of the numpy code this replaced, operation for operation (the same jumps, and so
   the same meshes and files): NaN coordinates (invalid nodes) make no jump.

   The points come as three planes x, y, z of rows x cols float64 values; the edges of one
   kind run from node (r, c + start_dc) to node (r + dr, c + end_dc), one output byte each
   (rows - dr rows of cols - max(start_dc, end_dc) edges). */

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>

enum { JUMPS_OK = 0, JUMPS_BAD_SHAPE = 1 };
enum { PLANAR = 0, CYLINDRICAL = 1, SPHERICAL = 2 };

/* Whether the edge from node s to node e is a jump. Most edges lie far from their node line
   (at more than 60 degrees, |e . m| < |e| |m| / 2, m the midpoint or +z): no square root
   or division settles those, and the test below could only give 0 for them (its rounding
   is some 1e-16 of the sizes, the margin from cos 60 to cos(angle) about 1). NaN gives 0. */
static int is_jump(const double *x, const double *y, const double *z, Py_ssize_t s, Py_ssize_t e, int projection,
                   double cosine)
{
    double ex = x[e] - x[s], ey = y[e] - y[s], ez = z[e] - z[s];
    double mx = 0.0, my = 0.0, mz = 1.0;
    if (projection != PLANAR) {
        mx = (x[s] + x[e]) / 2;
        my = projection == CYLINDRICAL ? 0.0 : (y[s] + y[e]) / 2;
        mz = (z[s] + z[e]) / 2;
    }
    double dot = ex * mx + ey * my + ez * mz;
    if (!(dot * dot >= 0.25 * (ex * ex + ey * ey + ez * ez) * (mx * mx + my * my + mz * mz)))
        return 0;
    double lx = 0.0, ly = 0.0, lz = 1.0;   /* the node line's unit direction, as numpy made it */
    if (projection != PLANAR) {
        double length = sqrt(mx * mx + my * my + mz * mz);
        double scale = length > 0 ? 1.0 / length : 0.0;
        lx = mx * scale;
        ly = my * scale;
        lz = mz * scale;
    }
    double along = ex * lx + ey * ly + ez * lz;
    return fabs(along) > cosine * sqrt(ex * ex + ey * ey + ez * ez);
}

static void find_jumps(uint8_t *out, const double *x, const double *y, const double *z, Py_ssize_t rows,
                       Py_ssize_t cols, int dr, int start_dc, int end_dc, int projection, double cosine)
{
    Py_ssize_t out_cols = cols - (start_dc > end_dc ? start_dc : end_dc);
    for (Py_ssize_t r = 0; r + dr < rows; r++)
        for (Py_ssize_t c = 0; c < out_cols; c++)
            out[r * out_cols + c] = (uint8_t)is_jump(x, y, z, r * cols + c + start_dc, (r + dr) * cols + c + end_dc,
                                                     projection, cosine);
}

static PyObject *jumps(PyObject *self, PyObject *args)
{
    Py_buffer out, x, y, z;
    Py_ssize_t rows, cols;
    int dr, start_dc, end_dc, projection;
    double cosine;
    (void)self;
    if (!PyArg_ParseTuple(args, "w*y*y*y*nniiiid", &out, &x, &y, &z, &rows, &cols, &dr, &start_dc, &end_dc,
                          &projection, &cosine))
        return NULL;
    int status = JUMPS_BAD_SHAPE;
    int widest = start_dc > end_dc ? start_dc : end_dc;
    if (rows >= 0 && cols >= 0 && (rows == 0 || cols <= PY_SSIZE_T_MAX / 8 / rows)
        && (dr == 0 || dr == 1) && (start_dc == 0 || start_dc == 1) && (end_dc == 0 || end_dc == 1)
        && projection >= PLANAR && projection <= SPHERICAL && x.len == rows * cols * (Py_ssize_t)sizeof(double)
        && y.len == x.len && z.len == x.len
        && out.len == (rows > dr ? rows - dr : 0) * (cols > widest ? cols - widest : 0)) {
        status = JUMPS_OK;
        if (out.len) {
            Py_BEGIN_ALLOW_THREADS
            find_jumps(out.buf, x.buf, y.buf, z.buf, rows, cols, dr, start_dc, end_dc, projection, cosine);
            Py_END_ALLOW_THREADS
        }
    }
    PyBuffer_Release(&out); PyBuffer_Release(&x); PyBuffer_Release(&y); PyBuffer_Release(&z);
    return PyLong_FromLong(status);
}

static PyMethodDef methods[] = {
    {"jumps", jumps, METH_VARARGS,
     "jumps(out, x, y, z, rows, cols, dr, start_dc, end_dc, projection, cosine) -> status: one byte per edge "
     "from node (r, c + start_dc) to node (r + dr, c + end_dc), 1 where it is a depth jump."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_jumps", "Depth jumps of a grid's edges.", -1, methods,
                                    NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__jumps(void)
{
    return PyModule_Create(&module);
}
