/* LZF decompression for PCD's binary_compressed bodies (mzc/meshes/pcd.py).
 *
 * LZF (Marc Lehmann's liblzf, the coder PCL writes) is a byte stream of runs: a control
 * byte c < 32 is followed by c + 1 literal bytes; otherwise its top 3 bits are a length
 * (7: add the next byte) and the low 5 bits with the next byte a distance back into the
 * output, from which length + 2 bytes are copied (overlapping copies repeat bytes).
 *
 * decompress(src, dst) fills the writable buffer dst and returns the number of bytes
 * written, or a negative code: every read and write is checked against its buffer first,
 * so a hostile stream can neither read nor write outside them.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#define LZF_TRUNCATED -1   /* the input ends inside a run */
#define LZF_OVERFLOW -2    /* the output would exceed dst */
#define LZF_BAD_DISTANCE -3  /* a back-reference before the start of the output */

static Py_ssize_t lzf_decode(const unsigned char *in, Py_ssize_t in_len, unsigned char *out, Py_ssize_t out_len)
{
    Py_ssize_t ip = 0, op = 0;
    while (ip < in_len) {
        unsigned int control = in[ip++];
        if (control < 32) {
            Py_ssize_t length = (Py_ssize_t)control + 1;
            if (length > in_len - ip) return LZF_TRUNCATED;
            if (length > out_len - op) return LZF_OVERFLOW;
            memcpy(out + op, in + ip, (size_t)length);
            ip += length;
            op += length;
        } else {
            Py_ssize_t length = control >> 5;
            if (length == 7) {
                if (ip >= in_len) return LZF_TRUNCATED;
                length += in[ip++];
            }
            length += 2;
            if (ip >= in_len) return LZF_TRUNCATED;
            Py_ssize_t distance = ((Py_ssize_t)(control & 0x1f) << 8) + in[ip++] + 1;
            if (distance > op) return LZF_BAD_DISTANCE;
            if (length > out_len - op) return LZF_OVERFLOW;
            for (Py_ssize_t k = 0; k < length; k++, op++) out[op] = out[op - distance];
        }
    }
    return op;
}

static PyObject *decompress(PyObject *self, PyObject *args)
{
    Py_buffer src, dst;
    (void)self;
    if (!PyArg_ParseTuple(args, "y*w*", &src, &dst)) return NULL;
    Py_ssize_t produced;
    Py_BEGIN_ALLOW_THREADS
    produced = lzf_decode((const unsigned char *)src.buf, src.len, (unsigned char *)dst.buf, dst.len);
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&src);
    PyBuffer_Release(&dst);
    return PyLong_FromSsize_t(produced);
}

static PyMethodDef methods[] = {
    {"decompress", decompress, METH_VARARGS,
     "decompress(src, dst) -> bytes written to dst, or -1 (input cut short), -2 (dst too small), "
     "-3 (a back-reference before the start)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_lzf", "LZF decompression, bounds-checked.", -1, methods,
                                    NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__lzf(void) { return PyModule_Create(&module); }
