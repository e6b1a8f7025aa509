"""Coverage-guided fuzzing of every mzc reader with atheris (libFuzzer for Python), for long runs
outside the test suite (README.md beside this file says how to run it).

An input is one byte choosing the kind (an index into readers.KINDS), then the bytes to read as
that kind; ``--seeds DIR`` writes the repository's real files of every kind (readers.seeds) into
DIR as such inputs, the corpus libFuzzer starts from. An input passes when its reader returns
a sane result or raises one MzcError of one line (readers.read), without a warning but mzc's own
(MzcWarning: a cut progressive dwt2d file's); anything
else is a crash that libFuzzer saves, and its ``-timeout`` and ``-rss_limit_mb`` bound each
input's time and memory. MZC_FUZZ_KINDS (comma-separated) keeps the inputs of some kinds only.
"""

import hashlib
import os
import sys
import warnings
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parents[1])]   # tests/, for fuzz.readers

import atheris  # noqa: E402 - after the path

from fuzz.readers import KINDS, read, seeds  # noqa: E402

with atheris.instrument_imports(include=["mzc"]):
    import mzc.codecs.dwt2d.entropy  # noqa: F401 - each reader's modules, instrumented for coverage
    import mzc.codecs.rows.legacy  # noqa: F401
    import mzc.formats.zgrid  # noqa: F401
    import mzc.meshes.las  # noqa: F401
    import mzc.meshes.meshio_fallback  # noqa: F401
    import mzc.meshes.obj  # noqa: F401
    import mzc.meshes.pcd  # noqa: F401
    import mzc.meshes.ply  # noqa: F401
    import mzc.meshes.stl  # noqa: F401
    import mzc.meshes.xyz  # noqa: F401
    import mzc.rasters.asc  # noqa: F401
    import mzc.rasters.geotiff  # noqa: F401
    from mzc.codecs import BUILT_IN, get_codec
    from mzc.errors import MzcError, MzcWarning

    for name in BUILT_IN:
        get_codec(name)

CHOSEN = [kind for kind in os.environ.get("MZC_FUZZ_KINDS", ",".join(KINDS)).split(",") if kind in KINDS]


def one_input(data: bytes) -> None:
    """Read one input: its first byte picks the kind, the rest is the file."""
    if not data:
        return
    kind = CHOSEN[data[0] % len(CHOSEN)]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            warnings.simplefilter("ignore", MzcWarning)   # mzc's own: a cut dwt2d 9.0 file's, by design
            read(kind, data[1:])
    except MzcError as error:
        if "\n" in str(error):
            raise AssertionError(f"an MzcError of more than one line: {error}") from None


def write_seeds(folder: Path) -> None:
    """The real files of every chosen kind as inputs in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for kind in CHOSEN:
        for data in seeds(kind):
            entry = bytes([CHOSEN.index(kind)]) + data
            (folder / f"{kind}-{hashlib.sha1(entry).hexdigest()[:12]}").write_bytes(entry)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--seeds"]:
        write_seeds(Path(sys.argv[2]))
    else:
        atheris.Setup(sys.argv, one_input)
        atheris.Fuzz()
