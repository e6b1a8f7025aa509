"""Where the shared data lies beside the checkout, and which of its files a benchmark measures:
one home for the paths and the globs every script used to spell out for itself. Importing it
has no side effects (no environment, no ``sys.path``), so scripts that time subprocesses use it
as freely as the others.
"""

import sys
from pathlib import Path

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
FACES = DATA / "faces"
OBJECTS = DATA / "objects"
MESH_SUFFIXES = (".ply", ".obj")


def mesh_files(folder):
    """The PLY and OBJ files of ``folder``, sorted by name; empty when the folder is absent (the
    shared data is not on every machine, and a benchmark then says so and skips)."""
    folder = Path(folder)
    return sorted(p for p in folder.glob("*") if p.suffix in MESH_SUFFIXES) if folder.is_dir() else []


def faces_measured(script, quick, least=1, quick_count=4):
    """The faces a benchmark measures: every one, or with ``quick`` the first ``quick_count``; the
    ``script`` exits naming the folder when fewer than ``least`` are there (a prior needs others to
    learn from)."""
    faces = mesh_files(FACES)
    faces = faces[:quick_count] if quick else faces
    if len(faces) < least:
        sys.exit(f"{script}: needs {least} or more faces under {FACES}")
    return faces
