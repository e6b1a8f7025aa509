"""mzc: compress 3D surface patches into small, specified files and rebuild dense meshes.

The method follows a PhD thesis on cutting planes, per-row transforms and a PDE step
(see README.md and spec/). The package is a family of Unix filters; the numerics live in
plain functions over numpy arrays so they can be used without the command line.
"""

__version__ = "0.1.0"
