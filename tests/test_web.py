"""The browser decoder of web/ (issue 34): `node web/cli.mjs decode IN` writes, byte for byte,
the z-grid `mzc decode IN` writes, on every fixture, the spec's worked examples, and the faces
at several targets; a bad file gets one line on stderr, exit status 1 and nothing on stdout.
The dft and dct files, whose bits spec/arithmetic.md promises only for given numpy and SciPy
versions, decode to the same header and to values within one part in 10^12 (the fixtures'
promise). Skipped when node is not installed."""

import json
import random
import subprocess
import zlib

import numpy as np
import pytest

from mzc.codecs import dwt2d
from mzc.codecs.dwt2d import compact
from mzc.errors import MzcError
from mzc.formats import read_any, zgrid
from mzc.formats.header import split_magic
from mzc.grid import ZGrid

from codec_contract import FIXTURES, damaged, fixture_bytes, fixture_names, rechecksummed, spec_examples
from conftest import face_path, run_mzc
from web_node import NODE, WEB, needs_node

TO_1E12 = ("dft", "dct")   # decoded to one part in 10^12, not bit for bit

pytestmark = needs_node


def web_reads():
    """The major versions web/mzc.mjs reads of each kind, {kind: [oldest, newest]} (its READS)."""
    if NODE is None:
        return {}
    script = 'import("./mzc.mjs").then((m) => process.stdout.write(JSON.stringify(m.READS)))'
    return json.loads(subprocess.run([NODE, "-e", script], cwd=WEB, check=True, capture_output=True).stdout)


READS = web_reads()
SUPPORTED = tuple(READS)   # the kinds web/mzc.mjs decodes


def test_web_reads_every_version_of_the_fixtures():
    """READS names, for every kind web/ decodes, the newest major version of its fixtures: a
    version mzc gained since is a failure here, not a skip elsewhere."""
    newest = {}
    for name in fixture_names():
        kind, major, _ = split_magic(fixture_bytes(name), name)
        newest[kind] = max(newest.get(kind, 0), major)
    assert {kind: READS[kind][1] for kind in SUPPORTED} == {kind: newest[kind] for kind in SUPPORTED}


def web_fixtures():
    """The fixtures of the kinds web/ decodes."""
    return [name for name in fixture_names() if name.split("-")[0] in SUPPORTED]


def node_decode(path):
    """`node web/cli.mjs decode PATH` as a finished process."""
    return subprocess.run([NODE, str(WEB / "cli.mjs"), "decode", str(path)], capture_output=True)


def mzc_decode(path):
    """The z-grid `mzc decode PATH` writes (its default: raw float64)."""
    return run_mzc("decode", path, check=True).stdout


def kind_of(data):
    """The kind of an mzc file from its magic line (``mzc-KIND MAJOR.MINOR``)."""
    return data.split(b" ", 1)[0].decode()[4:]


def assert_same_zgrid(got, want, kind):
    """Equal bytes, or for TO_1E12 kinds the same header but for its crc32, NaN at the same
    nodes and values within 10^-12 of the largest |value| (a sum that cancels to near 0 keeps
    the rounding errors of its terms)."""
    if kind not in TO_1E12:
        assert got == want
        return
    without_crc = [[line for line in z.split(b"\ndata\n")[0].split(b"\n") if not line.startswith(b"crc32 ")]
                   for z in (got, want)]
    assert without_crc[0] == without_crc[1]
    got, want = read_any(got, "web.zg").z, read_any(want, "mzc.zg").z
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.nanmax(np.abs(want)))


def assert_decodes_alike(path):
    result = node_decode(path)
    assert result.returncode == 0, result.stderr.decode()
    assert_same_zgrid(result.stdout, mzc_decode(path), kind_of(path.read_bytes()))


@pytest.mark.parametrize("name", web_fixtures())
def test_every_fixture_decodes_as_mzc_decodes_it(name):
    assert_decodes_alike(FIXTURES / name)


DWT2D_TARGETS = (("--rmse", "0.05"), ("--rmse", "0.2"), ("--max-error", "0.2"), ("--max-error", "0.05"),
                 ("--size", "1500"))
ROW_CODECS = (("--poly", "8"), ("--poly", "12", "--basis", "power"), ("--dct", "-q", "30"), ("--dft", "-q", "30"),
              ("--dwt", "-q", "30"))
CASES: list[tuple[str, tuple[str, ...]]] = [(face, ("--dwt2d", *target)) for face in ("f18.ply", "m66.ply")
                                             for target in DWT2D_TARGETS]
CASES += [("f18.ply", codec) for codec in ROW_CODECS]
CASES += [("blob", ("--dwt2d", "--rmse", "0.05"))]   # a multi-chart grid (mzc-dwt2d 4.0) of a built-in sample


@pytest.fixture(scope="module")
def sliced(tmp_path_factory):
    """A surface's grid as mzc slices it, sliced once: sliced(name) -> path; a shared face by its
    file name, or the sample ``blob`` cut into six charts."""
    paths = {}

    def grid(name):
        if name not in paths:
            folder = tmp_path_factory.mktemp("web")
            if name == "blob":
                run_mzc("sample", "blob", "-o", folder / "blob.obj", check=True)
                run_mzc("slice", folder / "blob.obj", "--charts", "6", "-o", folder / "grid.zg", check=True)
            else:
                run_mzc("slice", face_path(name), "-o", folder / "grid.zg", check=True)
            paths[name] = folder / "grid.zg"
        return paths[name]
    return grid


@pytest.mark.parametrize("face, options", CASES, ids=[f"{face.removesuffix('.ply')} {' '.join(options)}"
                                                     for face, options in CASES])
def test_faces_at_several_targets_decode_as_mzc_decodes_them(sliced, face, options, tmp_path):
    path = tmp_path / "face.mzc"
    run_mzc("encode", *options, sliced(face), "-o", path, check=True)
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


def test_every_expected_zgrid_decodes_as_mzc_decodes_it():
    """The fixtures' expectations: plain z-grids of every kind of grid (a raw one for charts)."""
    paths = [FIXTURES / f"{name}.expected.zg" for name in fixture_names()]
    for path, result in zip(paths, node_decode_all(paths)):
        assert "zgrid" in result, (path.name, result)
        assert bytes.fromhex(result["zgrid"]) == python_decode(path.read_bytes(), path.name), path.name


def test_every_worked_example_decodes_as_mzc_decodes_it(tmp_path):
    examples = [case for kind in SUPPORTED for case in spec_examples(kind)]
    paths = [tmp_path / name for _, _, name in examples]
    for path, (data, _, _) in zip(paths, examples):
        path.write_bytes(data)
    for (data, _, name), result in zip(examples, node_decode_all(paths)):
        assert "zgrid" in result, (name, result)
        assert_same_zgrid(bytes.fromhex(result["zgrid"]), python_decode(data, name), kind_of(data))


def mutations(data, count, seed):
    """``count`` copies of ``data`` with 1 to 3 bytes changed, mostly in the body, each with its
    checksums (the crc32 line, or a 7.0 file's sections' CRC-32s) made right again so that the
    decoders' other checks are reached."""
    rng = random.Random(seed)
    spans = compact_sections(data) if compact.is_compact(data) else None
    body = spans[0][0] + 1 if spans else data.index(b"\ndata\n") + 6
    for _ in range(count):
        changed = bytearray(data)
        for _ in range(rng.choice((1, 1, 2, 3))):
            at = rng.randrange(body if rng.random() < 0.8 else 0, len(data))
            changed[at] = rng.randrange(256) if rng.random() < 0.5 else changed[at] ^ (1 << rng.randrange(8))
        if spans:
            yield sections_rechecksummed(changed, spans)
        elif b"\ndata\n" in changed:
            yield rechecksummed(bytes(changed))


def compact_sections(data):
    """The (start, end) of each section of a 7.0 or 8.0 file before its CRC-32 (the first from its tag);
    of a 9.0 file, of its header, base and whole level sections and its colour section, if whole; of a
    10.0 file, its one body (after the magic line) before its CRC-32."""
    reader = compact.Reader(data, "t")
    if compact.major(data) == compact.TIGHT_MAJOR:
        return [(reader.position, len(data) - compact.CRC.size)]
    if compact.major(data) == compact.PROGRESSIVE_MAJOR:
        start = reader.position
        reader.header()
        spans = [(start, reader.position - 4)]
        sections = compact.read_progressive(data, "t")
        ends = [*sections.ends, *([len(data)] if sections.colour is not None else [])]
        return spans + [(spans[-1][1] + 4 if i == 0 else ends[i - 1], end - 4) for i, end in enumerate(ends)]
    spans = []
    for tag in (compact.HEADER, compact.PAYLOAD):
        start = reader.position
        reader.section(tag, bytes(data[:start]) if tag == compact.HEADER else b"")
        spans.append((start, reader.position - 4))
    return spans


def sections_rechecksummed(changed, spans):
    """A 7.0 file edited on purpose with the CRC-32 of each of its original sections' spans made
    right again (the header's from the magic line on; a 9.0 file's each from the CRC-32 before it)."""
    chained = compact.major(changed) == compact.PROGRESSIVE_MAJOR
    for number, (start, end) in enumerate(spans):
        before = zlib.crc32(changed[start - 4:start]) if chained and number else 0
        changed[end:end + 4] = zlib.crc32(changed[0 if number == 0 else start:end], before).to_bytes(4, "little")
    return bytes(changed)


def known_divergence(result):
    """A file mzc decodes where the spec refuses it: a chart's view number below 0, which mzc
    reads as a Python index from the end (mzc.codecs.dwt2d.decode_charts checks only >= 6)."""
    return "view number -" in result.get("refused", "")


def test_narrow_and_small_grids_decode_as_mzc_decodes_them(tmp_path):
    """Grids of one or two columns or rows at one and two levels (a tiled file's last tiles):
    bands of one node, or of none, along an axis."""
    rng = np.random.default_rng(34)
    paths, expected = [], []
    for rows, cols in [(4, 1), (1, 4), (3, 1), (5, 1), (8, 1), (4, 2), (2, 4), (5, 2), (1, 1), (2, 2)]:
        for level in (1, 2):
            grid = ZGrid(np.round(10 + rng.normal(0, 1, (rows, cols)), 3), d1=1.5, d2=2)
            for compact_file in (False, True):   # the 3.1 file a tile is, and the 7.0 file of a whole grid
                data = dwt2d.encode_whole(grid, max_error=0.05, level=level, slope_limit=2, compact=compact_file)[0]
                paths.append(tmp_path / f"{rows}x{cols}-{level}-{compact_file}.mzw2")
                paths[-1].write_bytes(data)
                expected.append(python_decode(data, paths[-1].name))
    for path, want, result in zip(paths, expected, node_decode_all(paths)):
        assert "zgrid" in result, (path.name, result)
        assert bytes.fromhex(result["zgrid"]) == want, path.name


def full_turn_grid(rng, rows, cols, projection):
    """A rows x cols full turn (cols * d2 = 2 pi R, so the columns wrap) about R = 40 with random
    holes: a bumpy band whose invalid runs cross the seam and cut rows apart."""
    radius = 40.0
    u = np.arange(cols) * 2 * np.pi / cols
    z = 52 + 3 * np.sin(3 * u)[None, :] + np.linspace(0, 2, rows)[:, None] + rng.normal(0, 0.05, (rows, cols))
    z[rng.random((rows, cols)) < 0.15] = np.nan
    z[: rows // 3, :3] = np.nan
    z[: rows // 3, -2:] = np.nan
    return ZGrid(np.round(z, 3), d1=0.5, d2=2 * np.pi * radius / cols, origin=(-np.pi * radius, -rows / 4),
                 projection=projection, radius=radius)


def test_full_turns_with_holes_decode_as_mzc_decodes_them(tmp_path):
    """Full turns whose columns wrap (even widths: the lifting and the relevance wrap round the
    seam; odd ones do not) at 1 to 4 levels, both wavelets, cylindrical and spherical, with holes
    and invalid runs across the seam: web/ decodes them as mzc does, byte for byte."""
    rng = np.random.default_rng(3434)
    paths, expected = [], []
    cases = [(24, 40, 3, "bior4.4", "cylindrical"), (17, 38, 2, "bior2.2", "cylindrical"),
             (20, 33, 2, "bior4.4", "cylindrical"), (32, 64, 4, "bior4.4", "spherical"),
             (9, 12, 1, "bior2.2", "spherical"), (12, 6, 2, "bior4.4", "cylindrical")]
    for rows, cols, levels, wavelet, projection in cases:
        grid = full_turn_grid(rng, rows, cols, projection)
        assert grid.periodic
        data = dwt2d.encode_whole(grid, max_error=0.02, wavelet=wavelet, level=levels, slope_limit=2)[0]
        paths.append(tmp_path / f"{rows}x{cols}-{levels}-{wavelet}-{projection}.mzw2")
        paths[-1].write_bytes(data)
        expected.append(python_decode(data, paths[-1].name))
    for path, want, result in zip(paths, expected, node_decode_all(paths)):
        assert want is not None and "zgrid" in result, (path.name, result)
        assert bytes.fromhex(result["zgrid"]) == want, path.name


@pytest.mark.parametrize("name", web_fixtures())
def test_damaged_files_are_refused_or_decoded_as_mzc_decodes_them(name, tmp_path):
    """Every damaged variant (cut, a byte flipped, bytes added, and bytes changed under a
    right checksum) is refused with an MzcError, never another exception, where mzc refuses
    it, and otherwise decodes as mzc decodes it."""
    variants = [*damaged(fixture_bytes(name)), *mutations(fixture_bytes(name), 60, name)]
    paths = [tmp_path / f"{index}-{name}" for index in range(len(variants))]
    for path, variant in zip(paths, variants):
        path.write_bytes(variant)
    for path, variant, result in zip(paths, variants, node_decode_all(paths)):
        assert "crash" not in result, result.get("crash")
        expected = python_decode(variant, name)
        if expected is not None and known_divergence(result):
            continue
        assert (result.get("zgrid") is None) == (expected is None), (path.name, result)
        if expected is not None:
            assert_same_zgrid(bytes.fromhex(result["zgrid"]), expected, name.split("-")[0])
