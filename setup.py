"""Build mzc's compiled kernels: small C modules that take buffers (no numpy headers needed)."""
import sys

from setuptools import Extension, setup

FLAGS = [] if sys.platform == "win32" else ["-O2", "-ffp-contract=off"]   # the same floating point on every CPU


def kernel(name):
    """The C extension module ``name`` (dotted), built from the .c file of that path."""
    return Extension(name, [name.replace(".", "/") + ".c"], extra_compile_args=FLAGS)


setup(ext_modules=[
    kernel("mzc._elementary"),
    kernel("mzc.codecs.dwt2d._fill"),
    kernel("mzc.codecs.dwt2d._rows"),
    kernel("mzc.measure._nearest"),
    kernel("mzc.meshes._lzf"),
    kernel("mzc.ops._plate"),
    kernel("mzc.ops._raster"),
    kernel("mzc.ops._zipper"),
])
