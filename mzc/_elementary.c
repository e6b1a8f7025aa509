/* Elementary functions that give the same bits on every machine (mzc/elementary.py).
 *
 * numpy's exp, log, arctan2 and power take SIMD paths chosen at run time (AVX-512 ones
 * differ in the last bit from AVX2 ones), and the C library's differ between its builds
 * (an FMA variant is picked on CPUs that have it) and between systems. Slices, view
 * choices, the encoder's step search and the decoder's step factors must not. These are
 * written out in IEEE binary64 additions, multiplications and divisions only, in a fixed
 * order, and built with -ffp-contract=off (setup.py), so every CPU and compiler gives the
 * same bits. Accuracy: within 1 ulp of the true value for sin and cos (|x| < 2^20; beyond,
 * they are of x modulo binary64's 2 pi: the same everywhere, but not sin and cos of x), 2 ulp
 * for atan2, 1 ulp for exp, log and log2 (tests/test_elementary.py measures it against the
 * C library's).
 *
 * Constants are binary64 written exactly in hex: X_HI + X_LO splits carry a value to
 * about 107 bits; PIO2_1 and PIO2_2 keep 33 bits and LN2_HI 32, so their products with the
 * integer of a reduction are exact. Polynomial coefficients are Taylor's (1/n!, 1/n),
 * each rounded to nearest: on the reduced ranges the series' tails are below 1e-18.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>

static const double PIO2_1 = 0x1.921fb544p+0, PIO2_2 = 0x1.0b4611a6p-34, PIO2_3 = 0x1.3198a2e037073p-69;
static const double TWO_OVER_PI = 0x1.45f306dc9c883p-1;
static const double PI_HI = 0x1.921fb54442d18p+1, PI_LO = 0x1.1a62633145c07p-53;
static const double PIO2_HI = 0x1.921fb54442d18p+0, PIO2_LO = 0x1.1a62633145c07p-54;
static const double LN2_HI = 0x1.62e42feep-1, LN2_LO = 0x1.a39ef35793c76p-33;
static const double INV_LN2 = 0x1.71547652b82fep+0;
static const double SQRT_HALF = 0x1.6a09e667f3bcdp-1;
static const double EXP_OVERFLOW = 709.782712893384, EXP_UNDERFLOW = -745.1332191019412;

/* atan(j/8), j = 0..8, as hi + lo */
static const double ATAN_HI[9] = {0.0, 0x1.fd5ba9aac2f6ep-4, 0x1.f5b75f92c80ddp-3, 0x1.6f61941e4def1p-2,
                                  0x1.dac670561bb4fp-2, 0x1.1e00babdefeb4p-1, 0x1.4978fa3269ee1p-1,
                                  0x1.700a7c5784634p-1, 0x1.921fb54442d18p-1};
static const double ATAN_LO[9] = {0.0, -0x1.cd37686760c17p-59, 0x1.8ab6e3cf7afbdp-57, -0x1.c63aae6f6e918p-56,
                                  0x1.a2b7f222f65e2p-56, -0x1.928df287a668fp-58, 0x1.2419a87f2a458p-56,
                                  -0x1.8c34d25aadef6p-56, 0x1.1a62633145c07p-55};

/* 1/n! */
static const double F2 = 0x1p-1, F3 = 0x1.5555555555555p-3, F4 = 0x1.5555555555555p-5, F5 = 0x1.1111111111111p-7,
                    F6 = 0x1.6c16c16c16c17p-10, F7 = 0x1.a01a01a01a01ap-13, F8 = 0x1.a01a01a01a01ap-16,
                    F9 = 0x1.71de3a556c734p-19, F10 = 0x1.27e4fb7789f5cp-22, F11 = 0x1.ae64567f544e4p-26,
                    F12 = 0x1.1eed8eff8d898p-29, F13 = 0x1.6124613a86d09p-33, F14 = 0x1.93974a8c07c9dp-37,
                    F15 = 0x1.ae7f3e733b81fp-41, F16 = 0x1.ae7f3e733b81fp-45, F17 = 0x1.952c77030ad4ap-49,
                    F18 = 0x1.6827863b97d97p-53;
/* 1/n, n odd */
static const double I3 = 0x1.5555555555555p-2, I5 = 0x1.999999999999ap-3, I7 = 0x1.2492492492492p-3,
                    I9 = 0x1.c71c71c71c71cp-4, I11 = 0x1.745d1745d1746p-4, I13 = 0x1.3b13b13b13b14p-4,
                    I15 = 0x1.1111111111111p-4, I17 = 0x1.e1e1e1e1e1e1ep-5, I19 = 0x1.af286bca1af28p-5,
                    I21 = 0x1.8618618618618p-5;

/* sin of r in [-pi/4, pi/4]: r + r^3 (-1/3! + r^2 (1/5! - ...)) */
static double sin_kernel(double r)
{
    double r2 = r * r;
    double p = -F3 + r2 * (F5 + r2 * (-F7 + r2 * (F9 + r2 * (-F11 + r2 * (F13 + r2 * (-F15 + r2 * F17))))));
    return r + (r * r2) * p;
}

/* cos of r in [-pi/4, pi/4]: 1 - r^2/2 + r^4 (1/4! - ...) */
static double cos_kernel(double r)
{
    double r2 = r * r;
    double p = F4 + r2 * (-F6 + r2 * (F8 + r2 * (-F10 + r2 * (F12 + r2 * (-F14 + r2 * (F16 - r2 * F18))))));
    double half = 0.5 * r2, w = 1.0 - half;
    return w + (((1.0 - w) - half) + (r2 * r2) * p);   /* (1 - w) - half: what rounding w lost */
}

/* x - k pi/2 for the nearest integer k (x >= 0), and k mod 4 in *quadrant. Below 2^20, k pi/2
   is exact to 115 bits; beyond, x is first taken modulo binary64's 2 pi (fmod is exact): the
   same bits everywhere, but no longer close to the true value (mzc's angles stay far below). */
static double reduced(double x, int *quadrant)
{
    if (x >= 0x1p20) x = fmod(x, 2.0 * PI_HI);
    double k = floor(x * TWO_OVER_PI + 0.5);
    *quadrant = (int)(k - 4.0 * floor(k * 0.25));
    return ((x - k * PIO2_1) - k * PIO2_2) - k * PIO2_3;
}

/* sin(x) = -sin(-x) and cos(x) = cos(-x) exactly: both reduce |x| */
static double portable_sin(double x)
{
    if (!isfinite(x)) return x - x;
    double ax = fabs(x), sine;
    if (ax <= 0x1.921fb54442d18p-1) {
        sine = sin_kernel(ax);
    } else {
        int quadrant;
        double r = reduced(ax, &quadrant);
        sine = quadrant == 0 ? sin_kernel(r) : quadrant == 1 ? cos_kernel(r) : quadrant == 2 ? -sin_kernel(r)
                                                                                              : -cos_kernel(r);
    }
    return signbit(x) ? -sine : sine;
}

static double portable_cos(double x)
{
    if (!isfinite(x)) return x - x;
    double ax = fabs(x);
    if (ax <= 0x1.921fb54442d18p-1) return cos_kernel(ax);
    int quadrant;
    double r = reduced(ax, &quadrant);
    return quadrant == 0 ? cos_kernel(r) : quadrant == 1 ? -sin_kernel(r) : quadrant == 2 ? -cos_kernel(r)
                                                                                          : sin_kernel(r);
}

/* atan of u, |u| <= 1/16 */
static double atan_series(double u)
{
    double u2 = u * u;
    double p = -I3 + u2 * (I5 + u2 * (-I7 + u2 * (I9 + u2 * (-I11 + u2 * (I13 + u2 * (-I15 + u2 * I17))))));
    return u + (u * u2) * p;
}

/* atan of t in [0, 1]: atan(c) + atan((t - c) / (1 + t c)) with c the nearest multiple of 1/8 */
static double atan_unit(double t)
{
    int j = (int)floor(t * 8.0 + 0.5);
    if (j == 0) return atan_series(t);
    double c = j * 0.125;
    double u = (t - c) / (1.0 + t * c);
    return ATAN_HI[j] + (ATAN_LO[j] + atan_series(u));
}

static double portable_atan2(double y, double x)
{
    if (isnan(x) || isnan(y)) return x + y;
    double ax = fabs(x), ay = fabs(y), angle;
    if (ay == 0.0) {
        angle = signbit(x) ? PI_HI : 0.0;
    } else if (isinf(ax) && isinf(ay)) {
        angle = signbit(x) ? 3.0 * (PI_HI * 0.25) : PI_HI * 0.25;
    } else {
        if (ay <= ax) angle = atan_unit(ay / ax);                        /* within 45 degrees of the x axis */
        else angle = PIO2_HI - (atan_unit(ax / ay) - PIO2_LO);
        if (signbit(x)) angle = PI_HI - (angle - PI_LO);
    }
    return signbit(y) ? -angle : angle;
}

static double portable_exp(double x)
{
    if (isnan(x)) return x;
    if (x > EXP_OVERFLOW) return HUGE_VAL;
    if (x < EXP_UNDERFLOW) return 0.0;
    double k = floor(x * INV_LN2 + 0.5);
    double r = (x - k * LN2_HI) - k * LN2_LO;
    double p = F2 + r * (F3 + r * (F4 + r * (F5 + r * (F6 + r * (F7 + r * (F8 + r * (F9 + r * (F10
               + r * (F11 + r * (F12 + r * F13))))))))));
    return ldexp(1.0 + (r + (r * r) * p), (int)k);
}

/* log(1 + f) for 1 + f in [sqrt(1/2), sqrt(2)): f - s (f - R), s = f / (2 + f), R = 2 s^2 (1/3 + s^2/5 + ...) */
static double log_near_one(double f)
{
    double s = f / (2.0 + f), s2 = s * s;
    double series = 2.0 * s2 * (I3 + s2 * (I5 + s2 * (I7 + s2 * (I9 + s2 * (I11 + s2 * (I13 + s2 * (I15
                    + s2 * (I17 + s2 * (I19 + s2 * I21)))))))));
    return f - s * (f - series);
}

/* x = (1 + f) 2^e with 1 + f in [sqrt(1/2), sqrt(2)); 0 when x is not positive and finite */
static int split_log(double x, double *f)
{
    int e;
    double m = frexp(x, &e);
    if (m < SQRT_HALF) {
        m *= 2.0;
        e -= 1;
    }
    *f = m - 1.0;
    return e;
}

static double portable_log(double x)
{
    if (isnan(x) || x < 0.0) return NAN;
    if (x == 0.0) return -HUGE_VAL;
    if (isinf(x)) return x;
    double f;
    int e = split_log(x, &f);
    return e * LN2_HI + (log_near_one(f) + e * LN2_LO);
}

static double portable_log2(double x)
{
    if (isnan(x) || x < 0.0) return NAN;
    if (x == 0.0) return -HUGE_VAL;
    if (isinf(x)) return x;
    double f;
    int e = split_log(x, &f);
    return e + log_near_one(f) * INV_LN2;
}

/* ---------------------------------------------------------------- Python glue */

static int check_doubles(const Py_buffer *view, Py_ssize_t count, const char *name)
{
    if (view->itemsize != (Py_ssize_t)sizeof(double) || view->len != count * (Py_ssize_t)sizeof(double)
        || (uintptr_t)view->buf % sizeof(double)) {
        PyErr_Format(PyExc_ValueError, "%s: expected %zd aligned float64 values", name, count);
        return -1;
    }
    return 0;
}

typedef double (*unary)(double);

static PyObject *apply_unary(PyObject *args, unary function)
{
    Py_buffer x, out;
    if (!PyArg_ParseTuple(args, "y*w*", &x, &out)) return NULL;
    Py_ssize_t count = x.len / (Py_ssize_t)sizeof(double);
    int bad = check_doubles(&x, count, "x") || check_doubles(&out, count, "out");
    if (!bad) {
        const double *in = (const double *)x.buf;
        double *result = (double *)out.buf;
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t i = 0; i < count; i++) result[i] = function(in[i]);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&x);
    PyBuffer_Release(&out);
    if (bad) return NULL;
    Py_RETURN_NONE;
}

static PyObject *sin_(PyObject *self, PyObject *args) { (void)self; return apply_unary(args, portable_sin); }
static PyObject *cos_(PyObject *self, PyObject *args) { (void)self; return apply_unary(args, portable_cos); }
static PyObject *exp_(PyObject *self, PyObject *args) { (void)self; return apply_unary(args, portable_exp); }
static PyObject *log_(PyObject *self, PyObject *args) { (void)self; return apply_unary(args, portable_log); }
static PyObject *log2_(PyObject *self, PyObject *args) { (void)self; return apply_unary(args, portable_log2); }

static PyObject *atan2_(PyObject *self, PyObject *args)
{
    Py_buffer y, x, out;
    (void)self;
    if (!PyArg_ParseTuple(args, "y*y*w*", &y, &x, &out)) return NULL;
    Py_ssize_t count = y.len / (Py_ssize_t)sizeof(double);
    int bad = check_doubles(&y, count, "y") || check_doubles(&x, count, "x") || check_doubles(&out, count, "out");
    if (!bad) {
        const double *ys = (const double *)y.buf, *xs = (const double *)x.buf;
        double *result = (double *)out.buf;
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t i = 0; i < count; i++) result[i] = portable_atan2(ys[i], xs[i]);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&y);
    PyBuffer_Release(&x);
    PyBuffer_Release(&out);
    if (bad) return NULL;
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"sin", sin_, METH_VARARGS, "sin(x, out): out[i] = sin(x[i]), float64 buffers of one length."},
    {"cos", cos_, METH_VARARGS, "cos(x, out): out[i] = cos(x[i])."},
    {"exp", exp_, METH_VARARGS, "exp(x, out): out[i] = e ** x[i]."},
    {"log", log_, METH_VARARGS, "log(x, out): out[i] = the natural logarithm of x[i]."},
    {"log2", log2_, METH_VARARGS, "log2(x, out): out[i] = the base-2 logarithm of x[i] (exact at powers of 2)."},
    {"atan2", atan2_, METH_VARARGS, "atan2(y, x, out): out[i] = the angle of (x[i], y[i]) in [-pi, pi]."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_elementary",
                                    "Elementary functions with the same bits on every machine.", -1, methods,
                                    NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__elementary(void) { return PyModule_Create(&module); }
