"""Every reader of mzc as a fuzz target: what it reads, real bytes to start from, and a worker
process that reads one input at a time within a time and memory bound.

A target is a kind of file (``KINDS``): each mesh and cloud format by its extension, each
raster, the z-grid, every compressed kind and the thesis's files. Its seeds are the
repository's own real files of that kind (tests/fixtures/, tests/data/public/), or, where it
keeps none (OBJ, PLY, OFF, VTK, x y z), a small mesh of a sample written by mzc. A reader
passes an input when it is refused with one MzcError, or read into a sane result (finite
points, triangles that index them; a grid within mzc.limits); anything else (another
exception, a warning but mzc's own, a hang, memory far beyond the input) is a finding. (mzc's
own warnings, MzcWarning, are read results: a cut progressive dwt2d file decodes with one.)

The worker (``python tests/fuzz/readers.py``) reads length-prefixed (kind, bytes) requests
on stdin and answers each with one JSON line: its outcome, seconds and tracemalloc peak. It
runs under RLIMIT_AS (WORKER_MEMORY), so a runaway allocation ends in MemoryError there, and
the caller (``Worker``) kills it past a deadline: a fuzzer in the test process survives
every input. tests/test_fuzz_readers.py drives it with hypothesis in the suite;
atheris_readers.py calls ``read`` in process for long runs (README.md).
"""

from __future__ import annotations

import json
import os
import re
import select
import struct
import subprocess
import sys
import time
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]
FIXTURES, PUBLIC = TESTS / "fixtures", TESTS / "data" / "public"
MESHES = ("obj", "ply", "stl", "off", "vtk", "xyz", "pcd", "las")
CODECS = ("dwt2d", "poly", "dft", "dct", "dwt")
LEGACY = ("dft", "dct", "dwt")
KINDS = (*MESHES, "tif", "asc", "zgrid", *CODECS, *(f"legacy-{kind}" for kind in LEGACY))
WORKER_MEMORY = 3 << 30   # RLIMIT_AS of the worker: numpy, scipy and laspy take about 1 GB of address space
TOKENS = (b"nan", b"inf", b"-inf", b"1e308", b"-1", b"0", b"99999999999", b"1e100", b"4294967297", b"")
NUMBERS = (0, 1, 0x7F, 0x80, 0xFF, 0x7FFF, 0xFFFF, 0x7FFFFFFF, 0xFFFFFFFF, 4_000_000_000, 2**63 - 1, 2**64 - 1)


def read(kind: str, data: bytes) -> str:
    """Read ``data`` as ``kind``; a one-line summary of what was read, or the MzcError (raised)
    that refused it. Any other exception or a result that breaks a promise is raised too."""
    import numpy as np

    from mzc.grid import ZGrid
    from mzc.limits import MAX_MAGNITUDE

    item = read_item(kind, data)
    if isinstance(item, ZGrid):
        assert item.z.ndim == 2 and not np.isinf(item.z).any()
        assert np.nanmax(np.abs(item.z), initial=0) <= MAX_MAGNITUDE
        return f"{item.shape[0]} x {item.shape[1]} grid, {int(item.valid.sum())} valid"
    points, triangles = item.points, item.triangles
    assert np.isfinite(points).all() and points.ndim == 2 and points.shape[1] == 3
    assert triangles.size == 0 or (0 <= triangles.min() and triangles.max() < len(points))
    return f"{len(points)} points, {len(triangles)} triangles"


def read_item(kind, data):
    """What ``data`` holds, read as mzc reads a file of ``kind``: a mesh by its extension, a
    raster as slice and mzc.read take one (its bytes decide whether it is one), an mzc file or
    a thesis file."""
    if kind in MESHES:
        from mzc.meshes import mesh_from_bytes

        return mesh_from_bytes(data, f"fuzz.{kind}")
    if kind in ("tif", "asc"):
        from mzc.formats import read

        return read(data, f"fuzz.{kind}")
    if kind.startswith("legacy-"):
        from mzc.codecs.rows.legacy import read_legacy

        return read_legacy(data, "fuzz", kind.split("-", 1)[1])
    from mzc.formats import read_any

    return read_any(data, "fuzz")


def seeds(kind: str) -> list[bytes]:
    """Real files of ``kind`` to mutate (at least one)."""
    extension = {"tif": ".tif", "asc": ".asc", "pcd": ".pcd", "stl": ".stl", "las": ".la?"}.get(kind)
    if extension:
        return [path.read_bytes() for path in sorted(PUBLIC.glob(f"*{extension}"))]
    if kind in CODECS:
        return [path.read_bytes() for path in sorted(FIXTURES.glob(f"{kind}-*.mz*")) if ".expected" not in path.name]
    if kind == "zgrid":
        return zgrid_seeds()
    if kind.startswith("legacy-"):
        return [legacy_seed(kind.split("-", 1)[1])]
    return [written_mesh(kind)]


def zgrid_seeds():
    """The fixtures' expected grids (plain text), and one of them with a raw body."""
    from mzc.formats import zgrid

    plain = [path.read_bytes() for path in sorted(FIXTURES.glob("*.expected.zg"))[:4]]
    return [*plain, zgrid.write(zgrid.read(plain[0]), raw="float64")]


def legacy_seed(kind):
    """A thesis file of ``kind`` as the MATLAB code writes it (tests/test_codec_formats.py)."""
    sys.path.insert(0, str(TESTS))
    from test_codec_formats import legacy_grid, matlab_file

    return matlab_file(legacy_grid(), kind, 60)


def written_mesh(kind):
    """A small mesh of the bump sample (about 300 vertices) as mzc writes ``kind``; x y z text
    of its vertices for xyz; ascii PLY, which mzc does not write itself."""
    import mzc
    from mzc.meshes import mesh_to_bytes

    mesh = mzc.triangulate(mzc.slice(mzc.sample("bump"), 8.0, 8.0))
    if kind == "xyz":
        return "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in mesh.points.tolist()).encode()
    if kind == "ply":
        vertices = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in mesh.points.tolist())
        faces = "".join(f"3 {a} {b} {c}\n" for a, b, c in mesh.triangles.tolist())
        header = (f"ply\nformat ascii 1.0\nelement vertex {len(mesh.points)}\nproperty double x\n"
                  f"property double y\nproperty double z\nelement face {len(mesh.triangles)}\n"
                  "property list uchar int vertex_indices\nend_header\n")
        return (header + vertices + faces).encode()
    return mesh_to_bytes(mesh, kind)


def mutate(data: bytes, choices) -> bytes:
    """``data`` changed by 1 to 4 mutations, each drawn through ``choices``, an object with
    ``integer(low, high)`` (inclusive) and ``pick(sequence)`` (hypothesis or atheris's
    provider): a bit flipped, bytes overwritten with an interesting value, a number token of
    text replaced, a span cut, repeated or removed, the file cut short; a compressed file's
    checksum is made right again half the time, so its decoder sees the change."""
    for _ in range(choices.integer(1, 4)):
        data = one_mutation(data, choices) if data else bytes([choices.integer(0, 255)])
    if data.startswith(b"mzc-") and choices.integer(0, 1):
        data = rechecksummed(data)
    return data


def one_mutation(data, choices):
    """One of ``mutate``'s changes."""
    at = choices.integer(0, len(data) - 1)
    kind = choices.pick(("flip", "byte", "word", "token", "cut", "repeat", "remove", "truncate"))
    if kind == "flip":
        return data[:at] + bytes([data[at] ^ (1 << choices.integer(0, 7))]) + data[at + 1:]
    if kind == "byte":
        return data[:at] + bytes([choices.pick((0, 1, 0x7F, 0x80, 0xFF, 0x20, 0x0A))]) + data[at + 1:]
    if kind == "word":
        width = choices.pick((2, 4, 8))
        value = choices.pick(NUMBERS) % (1 << (8 * width))
        return data[:at] + value.to_bytes(width, "little") + data[at + width:]
    if kind == "token":
        numbers = list(re.finditer(rb"[-+]?[0-9][0-9.eE+-]*", data))
        if numbers:
            match = numbers[choices.integer(0, len(numbers) - 1)]
            return data[:match.start()] + choices.pick(TOKENS) + data[match.end():]
        return data
    end = min(len(data), at + choices.integer(1, 64))
    if kind == "cut":
        return data[:at] + data[end:]
    if kind == "repeat":
        return data[:end] + data[at:end] * choices.integer(1, 3) + data[end:]
    if kind == "remove":
        return data[:at] + data[at + 1:]
    return data[:at]


def rechecksummed(data):
    """An mzc file with its crc32 line (if it has one) made right for its bytes."""
    from mzc.formats.header import with_checksum

    stripped, found = re.subn(rb"crc32 [^\n]*\n", b"", data, count=1)
    return with_checksum(stripped) if found and b"\ndata\n" in stripped else data


def outcome(kind: str, data: bytes) -> dict:
    """What reading ``data`` as ``kind`` did: ``outcome`` ok, refused or error (with ``detail``),
    its ``seconds`` and the ``peak`` of Python's (and numpy's) allocations in bytes."""
    import tracemalloc
    import warnings

    from mzc.errors import MzcError, MzcWarning

    tracemalloc.start()
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            warnings.simplefilter("ignore", MzcWarning)   # mzc's own: a cut dwt2d 9.0 file's, by design
            result = {"outcome": "ok", "detail": read(kind, data)}
    except MzcError as error:
        result = {"outcome": "refused", "detail": str(error)}
        if "\n" in result["detail"]:
            result = {"outcome": "error", "detail": f"an MzcError of more than one line: {result['detail']!r}"}
    except BaseException as error:   # noqa: BLE001 - every other exception is what the fuzz looks for
        import traceback

        result = {"outcome": "error", "detail": "".join(traceback.format_exception(error))[-3000:]}
    result["seconds"] = time.perf_counter() - start
    result["peak"] = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return result


def serve():
    """The worker's loop: requests (kind and data, each a uint32 length and its bytes) from
    stdin, one JSON line of ``outcome`` each to stdout, under RLIMIT_AS."""
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (WORKER_MEMORY, WORKER_MEMORY))
    source, sink = sys.stdin.buffer, os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)   # whatever a reader prints goes to stderr, not into the answers
    while True:
        kind = take(source)
        if kind is None:
            return
        sink.write(json.dumps(outcome(kind.decode(), take(source))) + "\n")
        sink.flush()


def take(source):
    """One length-prefixed field, or None at the end of the input."""
    head = source.read(4)
    return source.read(struct.unpack("<I", head)[0]) if len(head) == 4 else None


class Worker:
    """A worker process (``serve``), restarted after an input it did not answer in time."""

    def __init__(self, deadline: float = 60.0):
        self.deadline, self.process = deadline, None

    def read(self, kind: str, data: bytes) -> dict:
        """``outcome`` of reading ``data`` as ``kind`` in the worker; ``timeout`` past the deadline."""
        if self.process is None:
            environment = {**os.environ, "PYTHONPATH": os.pathsep.join([str(TESTS.parent), str(TESTS)])}
            self.process = subprocess.Popen([sys.executable, __file__], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                            env=environment)
        request = b"".join(struct.pack("<I", len(field)) + field for field in (kind.encode(), data))
        self.process.stdin.write(request)
        self.process.stdin.flush()
        ready, _, _ = select.select([self.process.stdout], [], [], self.deadline)
        line = self.process.stdout.readline() if ready else b""
        if not line:
            self.close()
            return {"outcome": "timeout" if not ready else "error", "detail": "no answer from the worker",
                    "seconds": self.deadline, "peak": 0}
        return json.loads(line)

    def close(self):
        """End the worker."""
        if self.process is not None:
            self.process.kill()
            self.process.wait()
            self.process = None


if __name__ == "__main__":
    serve()
