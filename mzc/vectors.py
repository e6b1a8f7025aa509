"""Arithmetic on arrays of 3D points and vectors, (..., 3), written out component by component.

numpy reduces rows of three about 30x slower than the first axis of a transposed copy, and
hands products (``@``, ``np.dot``, ``np.linalg``) to BLAS, whose threads can stall for tens
of milliseconds on a busy machine and whose kernels are chosen by the CPU at run time
(OpenBLAS's Haswell, SkylakeX, Zen... kernels sum in other orders and fuse multiply-adds),
so their last bits differ from one machine to another. These functions do the same sums
as IEEE operations in a fixed order: fast, and the same bits everywhere. mzc never hands
its outputs' arithmetic to BLAS or LAPACK.
"""

import numpy as np

JACOBI_SWEEPS = 8   # a 3x3 symmetric matrix is diagonal to the last bit after 4-5 sweeps


def of_each_row(reduction, values):
    """``reduction`` (np.min, np.max, np.ptp or np.sum) of each row of an (n, k) array with few
    columns (a triangle's corners), as the reduction of a transposed copy's first axis."""
    return reduction(np.ascontiguousarray(values.T), axis=0)


def lengths(vectors):
    """The Euclidean length of each row of (n, k) ``vectors`` (np.linalg.norm(axis=1)'s values)."""
    return np.sqrt(of_each_row(np.sum, vectors * vectors))


def length(vector):
    """The Euclidean length of one vector (np.linalg.norm's value, without BLAS's dot)."""
    vector = np.asarray(vector, dtype=float)
    return float(np.sqrt(np.sum(vector * vector)))


def inner(a, b):
    """The inner product of two vectors of any length: numpy's pairwise sum of the products
    (np.dot hands it to BLAS, np.einsum to SIMD loops whose order depends on numpy's build)."""
    return float(np.sum(a * b))


def unit_scaled(solve, *values):
    """``solve(*values)`` for a ``solve`` linear in its ``values`` together (arrays, NaN where none,
    or None), worked on them scaled by the power of two that brings the largest finite one's size
    into [0.5, 1) and scaled back. A power of two scales every sum, product and quotient exactly,
    so values of any ordinary size come back as the same numbers bit for bit, and values near the
    ends of the floats' range as well as any others: conjugate gradients on heights of 1e-162
    divided by an inner product underflowed to 0. Values all 0 (or none finite) are solved as they are."""
    largest = max((float(np.max(np.abs(v), where=np.isfinite(v), initial=0.0)) for v in values if v is not None),
                  default=0.0)
    if not largest:
        return solve(*values)
    exponent = int(np.frexp(largest)[1])
    return np.ldexp(solve(*(None if v is None else np.ldexp(v, -exponent) for v in values)), exponent)


def dotted(vectors, others):
    """The dot product of (..., 3) ``vectors`` with (..., 3) ``others`` (one direction (3,), or one each)."""
    return vectors[..., 0] * others[..., 0] + vectors[..., 1] * others[..., 1] + vectors[..., 2] * others[..., 2]


def rotated(points, matrix):
    """``points @ matrix.T`` for (..., 3) ``points`` and a 3x3 ``matrix``: each point mapped by it
    (``dotted``'s sums, each component read from a contiguous copy: a third faster than strided)."""
    components = np.moveaxis(np.ascontiguousarray(np.moveaxis(np.asarray(points), -1, 0)), 0, -1)
    return np.stack([dotted(components, row) for row in np.asarray(matrix, dtype=np.float64)], axis=-1)


def matrix_product(a, b):
    """``a @ b`` for two 3x3 matrices (the columns of ``b`` mapped by ``a``)."""
    return rotated(np.asarray(b, dtype=float).T, a).T


def determinant(matrix):
    """The determinant of a 3x3 matrix: the triple product of its columns."""
    matrix = np.asarray(matrix, dtype=float)
    return float(dotted(np.cross(matrix[:, 0], matrix[:, 1]), matrix[:, 2]))


def symmetric_eigen(matrices):
    """(eigenvalues ascending (..., 3), unit eigenvectors as columns (..., 3, 3)) of symmetric
    3x3 ``matrices``, as np.linalg.eigh gives them, by cyclic Jacobi rotations: each zeroes
    one off-diagonal pair, JACOBI_SWEEPS times over the three, every matrix at once."""
    a = np.array(matrices, dtype=float)
    vectors = np.broadcast_to(np.eye(3), a.shape).copy()
    for _ in range(JACOBI_SWEEPS):
        for p, q in ((0, 1), (0, 2), (1, 2)):
            cosine, sine = jacobi_rotation(a[..., p, p], a[..., q, q], a[..., p, q])
            rotate_pair(a, vectors, p, q, cosine, sine)
    values = np.diagonal(a, axis1=-2, axis2=-1)
    order = np.argsort(values, axis=-1, kind="stable")
    return np.take_along_axis(values, order, -1), np.take_along_axis(vectors, order[..., None, :], -1)


def jacobi_rotation(app, aqq, apq):
    """(cos, sin) of the plane rotation that zeroes the symmetric pair a_pq (the smaller angle)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        theta = (aqq - app) / (2.0 * apq)
        tangent = np.where(apq == 0, 0.0, np.copysign(1.0, theta) / (np.abs(theta) + np.sqrt(theta * theta + 1.0)))
    tangent = np.where(np.isfinite(tangent), tangent, 0.0)
    cosine = 1.0 / np.sqrt(tangent * tangent + 1.0)
    return cosine, tangent * cosine


def rotate_pair(a, vectors, p, q, cosine, sine):
    """``a`` = J^T a J and ``vectors`` = vectors J in place, J the rotation in plane (p, q)."""
    c, s = cosine[..., None], sine[..., None]
    row_p, row_q = a[..., p, :].copy(), a[..., q, :].copy()
    a[..., p, :], a[..., q, :] = c * row_p - s * row_q, s * row_p + c * row_q
    column_p, column_q = a[..., :, p].copy(), a[..., :, q].copy()
    a[..., :, p], a[..., :, q] = c * column_p - s * column_q, s * column_p + c * column_q
    column_p, column_q = vectors[..., :, p].copy(), vectors[..., :, q].copy()
    vectors[..., :, p], vectors[..., :, q] = c * column_p - s * column_q, s * column_p + c * column_q
