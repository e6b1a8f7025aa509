"""The command runs whose output bytes must not change when the code is reorganised, nor
from one machine to another.

Each case is a chain of ``mzc`` commands run in-process (click's runner) on a built-in sample,
a shared face or a format fixture; the SHA-256 of every output is kept in
``tests/data/golden-outputs.json``. ``tests/test_unchanged_outputs.py`` reruns them and
compares, here and in subprocesses with numpy's AVX-512 and AVX2 loops switched off. After a
deliberate change of output (a new format version, a better default), rewrite the reference with

    python tests/golden.py --write

and say in the commit which outputs changed and why. ``python tests/golden.py --print``
prints the digests as JSON (what the subprocesses report).
"""

import hashlib
import json
import re
import sys
import tempfile
from pathlib import Path

from click.testing import CliRunner

from codec_contract import fixture_bytes, fixture_names

REPO = Path(__file__).resolve().parents[1]
FACES = REPO.parent / "shared" / "data" / "faces"
REFERENCE = REPO / "tests" / "data" / "golden-outputs.json"
SAMPLES = ("bump", "blob", "tube", "jacksboro", "topobathy")
DETAILED_FACES = ("f18.ply", "m66.ply", "example.obj")
MESHIO_STAMP = re.compile(rb"^comment Created by meshio[^\n]*\n", re.MULTILINE)
ALL_FORMATS = ("obj", "ply", "stl", "off", "vtk")
ALL_FORMATS_OF = ("bump", "tube")   # the other surfaces are written as OBJ and PLY only (STL is slow)
DIFFED = ("bump", "blob", "f18.ply")
CODECS = {
    "poly": ["--poly", "20"],
    "dft": ["--dft", "-q", "20"],
    "dct": ["--dct", "-q", "20", "--precision", "3"],
    "dwt": ["--dwt", "-q", "20", "--wavelet", "db2"],
    "max": ["--dwt2d", "--max-error", "0.05"],
    "rmse": ["--dwt2d", "--rmse", "0.05"],
    "size": ["--dwt2d", "--size", "3000"],
}


def run(arguments, stdin=b""):
    """The stdout bytes of ``mzc ARGUMENTS`` run in this process (an AssertionError if it fails)."""
    from mzc.cli import group

    result = CliRunner().invoke(group, [str(a) for a in arguments], input=stdin, catch_exceptions=False)
    if result.exit_code != 0:
        raise AssertionError(f"mzc {' '.join(map(str, arguments))} exited {result.exit_code}")
    return result.stdout_bytes


def run_to_file(arguments, path, stdin=b""):
    """The bytes that ``mzc ARGUMENTS -o PATH`` writes to PATH."""
    run([*arguments, "-o", path], stdin)
    return Path(path).read_bytes()


def digest(data):
    """The SHA-256 of ``data`` in hex, without the time stamp meshio writes into a PLY header."""
    return hashlib.sha256(MESHIO_STAMP.sub(b"", data)).hexdigest()


def sample_cases(folder):
    """Outputs of every command on the built-in samples: {case name: bytes}."""
    outputs = {}
    for name in SAMPLES:
        for file_format in formats_of(name):
            outputs[f"sample {name} -o .{file_format}"] = run_to_file(["sample", name],
                                                                      folder / f"{name}.{file_format}")
        mesh = folder / f"{name}.ply"
        outputs.update(surface_cases(name, mesh, detailed=True))
    return outputs


def formats_of(name):
    """The mesh formats written for surface ``name``."""
    return ALL_FORMATS if name in ALL_FORMATS_OF else ("obj", "ply")


def surface_cases(name, mesh, detailed):
    """Outputs of the pipeline on one mesh file; every command when ``detailed``."""
    outputs = {}
    grid = outputs[f"{name}: slice"] = run(["slice", mesh])
    codecs = CODECS if detailed else {"rmse": CODECS["rmse"]}
    for label, options in codecs.items():
        coded = outputs[f"{name}: encode {label}"] = run(["encode", *options], grid)
        outputs[f"{name}: decode {label}"] = run(["decode", "--plain", "--precision", "6"], coded)
        outputs[f"{name}: decode {label} exact"] = run(["decode"], coded)
    if not detailed:
        return outputs
    outputs[f"{name}: slice --thesis-grid"] = run(["slice", mesh, "--thesis-grid"])
    decoded = run(["decode"], outputs[f"{name}: encode rmse"])
    for method in ("biharmonic", "laplace", "thesis"):
        outputs[f"{name}: densify -n 2 {method}"] = run(["densify", "-n", "2", "--method", method, "--plain",
                                                         "--precision", "6"], decoded)
    folder = mesh.parent
    for file_format in formats_of(name):
        outputs[f"{name}: triangulate -o .{file_format}"] = run_to_file(["triangulate"],
                                                                       folder / f"out.{file_format}", decoded)
    outputs[f"{name}: triangulate"] = run(["triangulate"], decoded)
    outputs[f"{name}: info"] = run(["info"], outputs[f"{name}: encode max"])
    if name in DIFFED:
        (folder / "decoded.zg").write_bytes(decoded)
        outputs[f"{name}: diff"] = run(["diff", mesh, folder / "decoded.zg"])
    return outputs


def face_cases():
    """Outputs of the pipeline on the shared faces (none when the folder is absent)."""
    outputs = {}
    if not FACES.is_dir():
        return outputs
    for path in sorted(FACES.glob("*.ply")) + [FACES / "example.obj"]:
        with tempfile.TemporaryDirectory() as folder:
            copy = Path(folder) / path.name
            copy.write_bytes(path.read_bytes())
            outputs.update(surface_cases(path.name, copy, detailed=path.name in DETAILED_FACES))
    return outputs


def fixture_cases():
    """Every format fixture decoded to an exact (raw) z-grid: the decoders' promise of the same
    bits on every machine (spec/arithmetic.md)."""
    return {f"fixture {name}: decode": run(["decode"], fixture_bytes(name)) for name in fixture_names()}


def all_digests():
    """{case: SHA-256 of its output} for the samples, the fixtures and the faces."""
    with tempfile.TemporaryDirectory() as folder:
        outputs = {**sample_cases(Path(folder)), **fixture_cases(), **face_cases()}
    return {case: digest(data) for case, data in outputs.items()}


if __name__ == "__main__":
    if sys.argv[1:] == ["--write"]:
        REFERENCE.write_text(json.dumps(all_digests(), indent=1, sort_keys=True) + "\n")
        print(f"wrote {REFERENCE}")
    elif sys.argv[1:] == ["--print"]:
        print(json.dumps(all_digests(), sort_keys=True))
    else:
        sys.exit("usage: python tests/golden.py --write | --print")
