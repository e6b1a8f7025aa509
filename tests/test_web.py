"""The browser decoder of web/ (issue 34): `node web/cli.mjs decode IN` writes, byte for byte,
the z-grid `mzc decode IN` writes, on every fixture of a format it reads, the spec's worked
examples, and the faces at several targets; a bad file gets one line on stderr, exit status 1
and nothing on stdout. Skipped when node is not installed."""

import json
import shutil
import subprocess

import pytest

from codec_contract import FIXTURES, damaged, fixture_bytes, fixture_names, spec_examples
from conftest import face_path, run_mzc
from mzc.errors import MzcError
from mzc.formats import read_any, zgrid

WEB = FIXTURES.parents[1] / "web"
NODE = shutil.which("node")
SUPPORTED = ("dwt2d",)   # the kinds web/mzc.mjs decodes

pytestmark = pytest.mark.skipif(NODE is None, reason="node is not installed")


def node_decode(path):
    """`node web/cli.mjs decode PATH` as a finished process."""
    return subprocess.run([NODE, str(WEB / "cli.mjs"), "decode", str(path)], capture_output=True)


def mzc_decode(path):
    """The z-grid `mzc decode PATH` writes (its default: raw float64)."""
    return run_mzc("decode", path, check=True).stdout


def assert_decodes_alike(path):
    result = node_decode(path)
    assert result.returncode == 0, result.stderr.decode()
    assert result.stdout == mzc_decode(path)


@pytest.mark.parametrize("name", [n for n in fixture_names() if n.split("-")[0] in SUPPORTED])
def test_every_fixture_decodes_as_mzc_decodes_it(name):
    assert_decodes_alike(FIXTURES / name)


EXAMPLES = [case for kind in SUPPORTED for case in spec_examples(kind)]


@pytest.mark.parametrize("data, _expected, name", EXAMPLES, ids=[name for _, _, name in EXAMPLES])
def test_every_worked_example_decodes_as_mzc_decodes_it(data, _expected, name, tmp_path):
    path = tmp_path / "example"
    path.write_bytes(data)
    assert_decodes_alike(path)


TARGETS = (("--rmse", "0.05"), ("--rmse", "0.2"), ("--max-error", "0.2"), ("--max-error", "0.05"), ("--size", "1500"))


@pytest.fixture(scope="module", params=["f18.ply", "m66.ply"])
def face_grid(request, tmp_path_factory):
    """A shared face sliced once as mzc slices it."""
    path = tmp_path_factory.mktemp("web") / request.param.replace(".ply", ".zg")
    run_mzc("slice", face_path(request.param), "-o", path, check=True)
    return path


@pytest.mark.parametrize("target", TARGETS, ids=" ".join)
def test_faces_at_several_targets_decode_as_mzc_decodes_them(face_grid, target, tmp_path):
    path = tmp_path / "face.mzw2"
    run_mzc("encode", "--dwt2d", *target, face_grid, "-o", path, check=True)
    assert_decodes_alike(path)


def test_a_bad_file_gets_one_line_on_stderr_and_nothing_on_stdout(tmp_path):
    data = fixture_bytes("dwt2d-3.1.mzw2")
    for index, variant in enumerate([data[:len(data) // 2], data[:-1] + b"\xff", b"", b"mzc-dwt2d 9.0\ndata\n"]):
        path = tmp_path / f"bad{index}.mzw2"
        path.write_bytes(variant)
        result = node_decode(path)
        assert (result.returncode, result.stdout) == (1, b""), variant[:40]
        assert result.stderr.decode().startswith(f"mzc: {path}: ") and result.stderr.count(b"\n") == 1
    assert node_decode(tmp_path / "missing.mzw2").returncode == 1


DECODE_ALL = """
import { readFileSync } from "node:fs";
import { decode, writeZgrid, MzcError } from "./mzc.mjs";
const out = [];
for (const name of JSON.parse(readFileSync(0, "utf8"))) {
  try { out.push({ zgrid: Buffer.from(writeZgrid(decode(readFileSync(name)))).toString("hex") }); }
  catch (error) { out.push(error instanceof MzcError ? { refused: error.message } : { crash: String(error.stack) }); }
}
process.stdout.write(JSON.stringify(out));
"""


def node_decode_all(paths):
    """web/mzc.mjs on many files in one node process: each {zgrid: hex}, {refused} or {crash}."""
    result = subprocess.run([NODE, "--input-type=module", "-e", DECODE_ALL], cwd=WEB, check=True, capture_output=True,
                            input=json.dumps([str(p) for p in paths]).encode())
    return json.loads(result.stdout)


def python_decode(data, name):
    """What mzc decode writes for ``data``, or None where it refuses it."""
    try:
        return zgrid.write(read_any(data, name), raw="float64")
    except MzcError:
        return None


@pytest.mark.parametrize("name", [n for n in fixture_names() if n.split("-")[0] in SUPPORTED])
def test_damaged_files_are_refused_or_decoded_as_mzc_decodes_them(name, tmp_path):
    """Every damaged variant (cut, a byte flipped, bytes added) is refused with an MzcError,
    never another exception, where mzc refuses it, and otherwise decodes to mzc's bytes."""
    variants = list(damaged(fixture_bytes(name)))
    paths = [tmp_path / f"{index}-{name}" for index in range(len(variants))]
    for path, variant in zip(paths, variants):
        path.write_bytes(variant)
    for path, variant, result in zip(paths, variants, node_decode_all(paths)):
        assert "crash" not in result, result.get("crash")
        expected = python_decode(variant, name)
        assert (result.get("zgrid") is None) == (expected is None), (path.name, result)
        if expected is not None:
            assert bytes.fromhex(result["zgrid"]) == expected, path.name
