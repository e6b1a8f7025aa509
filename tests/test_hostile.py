"""A hostile corpus for the promises of issue 13 that are not about outputs or mesh files
(those are tests/test_outputs.py and tests/test_mesh_hostile.py; damaged compressed files
are tests/test_integrity.py): what mzc writes it reads back (class 3), no internal error
(4), work bounded by what the header and options declare (5), no noise on stderr (6), and
messages that name the right thing (7).

Every case runs the real command line in this process (``mzc.cli.main`` with its argv,
stdin and stdout replaced), so hundreds of cases stay fast, and checks the general promise
first: exit status 0, 1 or 2, at most one line on stderr, never "internal error", a
traceback or a warning of numpy's; a failure leaves stdout empty; and an mzc file written
is read back by ``mzc decode``.
"""

import io
import itertools
import math
import sys
import time
import warnings

import pytest

from mzc.formats import is_mzc, read_any
from mzc.formats.header import with_checksum

SMALL = "mzc-zgrid 1.0\nrows 3\ncols 4\nd1 1\nd2 1\norigin 0 0\ndata\n1 2 3 4\n2 3 nan 5\n3 4 5 6\n"
CODECS = [["--dwt2d", "--max-error", "0.1"], ["--dwt2d", "--rmse", "0.1"], ["--dwt2d", "--size", "300"],
          ["--dct", "-q", "50"], ["--dft", "-q", "50"], ["--dwt", "-q", "50"], ["--poly", "3"],
          ["--poly", "3", "--basis", "power"]]


class Run:
    """The outcome of one in-process command: exit status, stdout bytes, stderr lines, seconds."""

    def __init__(self, status, stdout, stderr, seconds):
        self.status, self.stdout, self.stderr, self.seconds = status, stdout, stderr, seconds


def run(*args, stdin=b""):
    """``mzc ARGS`` through mzc.cli.main in this process, stdin given as bytes."""
    from mzc.cli import main

    out, err = io.BytesIO(), io.StringIO()
    saved = sys.argv, sys.stdin, sys.stdout, sys.stderr
    sys.argv = ["mzc", *map(str, args)]
    sys.stdin = io.TextIOWrapper(io.BytesIO(stdin))
    sys.stdout = io.TextIOWrapper(out, write_through=True)
    sys.stderr = err
    start = time.perf_counter()
    status = 0
    try:
        with warnings.catch_warnings():
            main()
    except SystemExit as done:
        status = done.code if isinstance(done.code, int) else 1
    finally:
        sys.stdout.flush()
        written = out.getvalue()
        sys.argv, sys.stdin, sys.stdout, sys.stderr = saved
    return Run(status, written, err.getvalue().splitlines(), time.perf_counter() - start)


def kept_promises(result):
    """The general promise of every case; returns the result for case-specific checks."""
    assert result.status in (0, 1, 2), result.stderr
    assert len(result.stderr) <= 1, result.stderr
    text = " ".join(result.stderr)
    for word in ("internal error", "Traceback", "RuntimeWarning", "Warning:", "LAPACK", "On entry to"):
        assert word not in text, result.stderr
    if result.status:
        assert result.stdout == b"", "a failed command wrote output"
        assert result.stderr and result.stderr[0].startswith("mzc"), result.stderr
    elif is_mzc(result.stdout):
        read_any(result.stdout, "written")   # what mzc writes, mzc reads
    return result


def grid_text(values, nodata="nan", d1="1", d2="1", extra=""):
    """A z-grid of the given rows of value tokens."""
    rows = [" ".join(map(str, row)) for row in values]
    header = [f"rows {len(values)}", f"cols {len(values[0])}", f"d1 {d1}", f"d2 {d2}", "origin 0 0",
              f"nodata {nodata}", *filter(None, extra.split("\n"))]
    return ("\n".join(["mzc-zgrid 1.0", *header, "data", *rows]) + "\n").encode()


# --- class 3: what encode, slice and decode write, mzc reads back -------------------------

EXTREME_VALUES = [1e308, -1e308, 1.7976931348623157e308, 1e101, 1e100, 1e99, 1e-308, 5e-324, 1e15, -1e15]
EXTREME_GRIDS = [grid_text([[v, 1, 2, 3], [1, v, 2, 3], [0, 1, 2, v]]) for v in EXTREME_VALUES]
EXTREME_GRIDS += [grid_text([[1e300, -1e300, 1e300, -1e300]] * 3), grid_text([[0, 0, 0, 0]] * 3),
                  grid_text([[7, 7, 7, 7]] * 3), grid_text([[1, 2, 3, 4]], d1="1e-300", d2="1e300")]


@pytest.mark.parametrize("codec, grid", list(itertools.product(CODECS, EXTREME_GRIDS)))
def test_an_encoded_file_decodes_or_the_encoder_refuses(codec, grid):
    """Heights up to 1e308: a file is written that decodes to finite heights, or nothing is written."""
    result = kept_promises(run("encode", *codec, stdin=grid))
    if result.status == 0:
        decoded = read_any(result.stdout, "encoded")
        assert math.isfinite(float(abs(decoded.z[decoded.valid]).max()))


@pytest.mark.parametrize("value", EXTREME_VALUES)
def test_heights_too_large_to_code_are_refused_by_name(value):
    result = kept_promises(run("encode", "--dct", stdin=grid_text([[value, 1], [2, 3]])))
    assert (result.status == 1) == (abs(value) > 1e100)
    if result.status:
        assert "heights reach" in result.stderr[0] and "<stdin>" in result.stderr[0]


BAD_UNITS = ["m m", "mm\nrows 5", "mm\rdata", "", "a\tb", "\x00", "x" * 65, "mm\x7f", "mm#", "\udcff"]


@pytest.mark.parametrize("units", BAD_UNITS)
def test_units_that_would_not_read_back_are_refused(units, tmp_path):
    """slice --units writes one header token or nothing: spaces and control characters cannot inject lines."""
    mesh = tmp_path / "m.xyz"
    mesh.write_text("0 0 0\n1 0 0\n0 1 0\n1 1 1\n2 2 0\n2 0 1\n0 2 1\n")
    result = kept_promises(run("slice", mesh, "--units", units))
    if units == "mm#":
        assert result.status == 0 and read_any(result.stdout, "s").units == "mm#"
    else:
        assert result.status == 2 and "--units" in result.stderr[0]


@pytest.mark.parametrize("nodata, precision", list(itertools.product(["0", "1", "-9999", "0.5", "NA", "nan"],
                                                                    ["0", "1", "2"])))
def test_a_valid_value_is_never_written_as_the_no_data_marker(nodata, precision):
    """decode/densify --precision: every valid node of the input stays valid, or the command refuses."""
    grid = grid_text([[0.3, 1.2, 0.6, nodata], [-9999, 0.5, 0.04, 2]], nodata=nodata)
    valid = read_any(grid, "in").valid.sum()
    rounded = ["--plain", "--precision", precision]
    for command in (["decode", *rounded], ["densify", "-n", "1", *rounded]):
        result = kept_promises(run(*command, stdin=grid))
        if result.status == 0 and command[0] == "decode":
            assert read_any(result.stdout, "out").valid.sum() == valid
        elif result.status:
            assert "no-data marker" in result.stderr[0]


# --- class 4: no internal error -----------------------------------------------------------

def coded(*codec):
    """The bytes of SMALL coded with ``codec``."""
    return run("encode", *codec, stdin=SMALL.encode()).stdout


HOSTILE_COMMANDS = [
    (["diff", "-", "-", "--seed", "-1"], SMALL),
    (["diff", "-", "-", "--seed", "99999999999999999999999"], SMALL),
    (["encode", "--poly", "300", "--basis", "power"], SMALL),
    (["encode", "--poly", "10000", "--basis", "power"], SMALL),
    (["encode", "--poly", "10001"], SMALL),
    (["encode", "--dct", "-q", "0"], SMALL),
    (["encode", "--dwt2d", "--max-error", "5e-324"], SMALL),
    (["encode", "--dwt2d", "--max-error", "1e308"], SMALL),
    (["encode", "--dwt2d", "--size", "1"], SMALL),
    (["encode", "--dwt2d", "--rmse", "inf"], SMALL),
    (["encode", "--dwt2d", "--rmse", "nan"], SMALL),
    (["encode", "--dwt2d", "--max-error", "0.1", "--level", "12"], SMALL),
    (["densify", "-n", "1", "--tol", "nan"], SMALL),
    (["densify", "-n", "1", "--jump-angle", "nan"], SMALL),
    (["slice", "--d1", "5e-324"], "0 0 0\n1 0 0\n0 1 1\n1 1 0\n"),
    (["slice", "--d1", "1e308"], "0 0 0\n1 0 0\n0 1 1\n1 1 0\n"),
    (["slice", "--rows", "0"], "0 0 0\n1 0 0\n0 1 1\n1 1 0\n"),
    (["slice", "--align", "pca"], "1e200 1e200 1e200\n-1e200 1e200 0\n1e200 -1e200 5\n0 0 1e200\n"),
    (["slice", "--align", "pca"], "0 0 0\n0 0 0\n0 0 0\n"),
    (["slice", "--center", "nan", "0", "0", "--projection", "cylindrical"], "0 0 0\n1 0 0\n0 1 1\n1 1 0\n"),
    (["slice", "--axis", "0", "0", "0", "--projection", "cylindrical"], "0 0 0\n1 0 0\n0 1 1\n1 1 0\n"),
    (["triangulate", "--format", "nonsense"], SMALL),
    (["info"], ""),
    (["info"], "mzc-"),
    (["decode"], "mzc-dwt2d 3.1\n"),
    (["decode", "--legacy", "dct"], "0.5 0.5 10 99999999 50\n"),
    (["decode", "--legacy", "poly"], "k1 10\nk2 ²\nD1 1\nD2 1\n"),
    (["sample", "nonsense"], ""),
]
HOLES_LINES = ["holes ²", "holes ١", "holes 1_0", "holes -1", "holes 1\n² 2 2", "holes 1\n1 ³ 2", "holes 1\n1 2",
               "holes 1\n99999999999999999999 2 3", "holes 1\n1 2 1", "holes nan"]


@pytest.mark.parametrize("args, stdin", HOSTILE_COMMANDS, ids=[" ".join(a) for a, _ in HOSTILE_COMMANDS])
def test_hostile_commands_fail_in_one_line_or_succeed(args, stdin):
    kept_promises(run(*args, stdin=stdin.encode()))


@pytest.mark.parametrize("holes", HOLES_LINES)
def test_odd_digits_in_a_holes_section_are_one_line_errors(holes):
    """A superscript or other non-ASCII digit (which str.isdigit() takes and int() may not)."""
    data = coded("--dct", "-q", "50")
    header, body = data.split(b"\ndata\n")
    rows = body.decode().split("holes")[0]
    damaged = with_checksum(header.split(b"\ncrc32")[0] + b"\ndata\n" + (rows + holes + "\n").encode())
    result = kept_promises(run("decode", stdin=damaged))
    assert result.status == 1 and "holes" in result.stderr[0]


# --- class 5: work bounded by what the header and options declare --------------------------

HUGE_HEADERS = [f"mzc-{kind} {version}\n{codec}rows {rows}\ncols {cols}\nd1 1\nd2 1\n"
                for kind, version, codec in [("zgrid", "1.0", ""), ("dct", "1.0", "quality 50\n"),
                                             ("poly", "1.0", "basis chebyshev\ndegree 10000\n"),
                                             ("dwt2d", "3.0", "steps 1\n"), ("dft", "1.0", "quality 50\n"),
                                             ("dwt", "1.0", "quality 50\nwavelet db1\nlevel 3\n")]
                for rows, cols in [(10**6, 10**6), (10**7, 1), (1, 10**7), (10**5, 10**4), (0, 5),
                                   (-1, 5), (99999999999999999999, 1)]]


@pytest.mark.parametrize("header", HUGE_HEADERS)
def test_a_declared_size_is_checked_before_any_work(header):
    """A few bytes declaring a grid too large are refused at once, by decode and by info."""
    for command in ("decode", "info"):
        result = kept_promises(run(command, stdin=(header + "data\n").encode()))
        assert result.status == 1 and result.seconds < 2


def test_info_reads_the_header_only():
    """A 10^4 x 10^4 dwt2d file of 80 bytes: info answers at once, without decoding 10^8 nodes."""
    data = b"mzc-dwt2d 3.0\nrows 10000\ncols 10000\nd1 1\nd2 1\nsteps 1\ndata\n\x00\x00"
    result = kept_promises(run("info", stdin=data))
    assert result.status == 0 and result.seconds < 2 and b"10000 rows x 10000 cols" in result.stdout


@pytest.mark.parametrize("args", [["densify", "-n", "21"], ["densify", "-n", "50"], ["densify", "-n", "1000000"],
                                  ["densify", "-n", "1", "--method", "thesis", "--iterations", "1000000000"],
                                  ["diff", "-", "-", "--surface", "--samples", "10000000"]])
def test_options_that_ask_for_unbounded_work_are_capped(args):
    result = kept_promises(run(*args, stdin=SMALL.encode()))
    assert result.status == 2 and result.seconds < 2


def test_a_poly_file_of_high_degree_decodes_in_bounded_memory():
    """degree 2000 on a row of 3000 samples: the evaluation goes in pieces (mzc.codecs.rows.transforms)."""
    import numpy as np

    from mzc.api import as_grid
    from mzc.codecs.rows import poly

    row = np.sin(np.linspace(0, 30, 3000))
    data = poly.write(as_grid(row[None, :]), degree=2000, precision=12)
    assert np.abs(poly.read(data).z[0] - row).max() < 1e-3


# --- class 6: no noise ---------------------------------------------------------------------

NASTY_GRIDS = [grid_text([[5, 5, 5, 5]] * 3), grid_text([["nan"] * 4, [1, 2, 3, 4], ["nan"] * 4]),
               grid_text([[1]]), grid_text([[1, 2, 3, 4]]), grid_text([[1], [2], [3]]),
               grid_text([[1, "nan"], ["nan", 2]]), grid_text([[0, 1e-300], [1e-300, 0]]),
               grid_text([[1e99, -1e99], [1e99, -1e99]]), grid_text([[1, 2], [3, 4]], d1="1e-300", d2="1e-300"),
               grid_text([[1, 2], [3, 4]], d1="1e300", d2="1e300")]
NASTY_COMMANDS = [["densify", "-n", "2"], ["densify", "-n", "2", "--method", "laplace"],
                  ["densify", "-n", "2", "--method", "thesis"], ["triangulate", "--format", "obj"],
                  ["diff", "-", "-"], ["diff", "-", "-", "--surface", "--samples", "100"], ["info", "--decode"],
                  *(["encode", *codec] for codec in CODECS)]


@pytest.mark.parametrize("command, grid", list(itertools.product(NASTY_COMMANDS, NASTY_GRIDS)))
def test_numerically_nasty_grids_make_no_noise(command, grid):
    """Constant, one-node, one-row, one-column, mostly invalid, tiny and huge grids through every
    command: a result or one line, and never a numpy, scipy or LAPACK warning."""
    kept_promises(run(*command, stdin=grid))


# --- class 7: messages that name the right thing ---------------------------------------------

def test_a_too_fine_d1_names_d1():
    result = kept_promises(run("slice", "--d1", "5e-324", "--d2", "1", stdin=b"0 0 0\n1 0 0\n0 1 1\n1 1 0\n"))
    assert result.status == 1 and ": d1: " in result.stderr[0]


@pytest.mark.parametrize("line, field", [("0.5 0.5 10 99999999 50", "k2"), ("0.5 0.5 99999999 10 50", "k1")])
def test_a_bad_legacy_size_names_its_own_field(line, field):
    result = kept_promises(run("decode", "--legacy", "dct", stdin=(line + "\n").encode()))
    assert result.status == 1 and f": {field}: " in result.stderr[0]


@pytest.mark.parametrize("chosen", [["--rmse", "--max"], [], ["--r2"]])
def test_a_diff_of_surfaces_that_do_not_overlap_says_so(chosen, tmp_path):
    a, b = tmp_path / "a.zg", tmp_path / "b.zg"
    a.write_bytes(grid_text([[1, 2], [3, 4]]))
    b.write_bytes(grid_text([[1, 2], [3, 4]]).replace(b"origin 0 0", b"origin 100 100"))
    result = kept_promises(run("diff", a, b, *chosen))
    assert result.status == 1 and "do not overlap" in result.stderr[0]


@pytest.mark.parametrize("args, expected", [
    (["encode", "--dct", "-q", "0"], "mzc encode: -q/--quality: 0 is not in 1..100"),
    (["densify", "-n", "-1"], "mzc densify: -n: -1 is not in 0..20"),
    (["encode", "--dwt2d", "--max-error", "-1"], "mzc encode: --max-error: -1.0 must be > 0 and <= 1e+100"),
])
def test_a_usage_error_starts_with_the_option_and_the_problem(args, expected):
    result = kept_promises(run(*args, stdin=SMALL.encode()))
    assert result.status == 2 and result.stderr[0].startswith(expected)


@pytest.mark.parametrize("args, grid", [
    (["encode", "--poly", "10000", "--basis", "power"], SMALL.encode()),
    (["encode", "--poly", "30", "--basis", "power"], grid_text([[1, 2, 3, 4]] * 3, d1="1e-45", d2="1e-45")),
    (["densify", "-n", "3"], grid_text([[1, 2], [3, 4]], d1="1e-49", d2="1e49")),
    (["encode", "--dwt2d", "--max-error", "1e-90"], grid_text([[1e99, 0], [0, -1e99]])),
])
def test_no_library_prints_to_the_stderr_file_itself(mzc, args, grid):
    """LAPACK's ``** On entry to ...`` lines bypass Python's sys.stderr: run as a process to see them."""
    result = mzc(*args, input=grid)
    assert result.returncode in (0, 1) and len(result.stderr.decode().splitlines()) <= 1, result.stderr


@pytest.mark.parametrize("codec", CODECS, ids=[" ".join(c) for c in CODECS])
def test_a_unit_outside_ascii_survives_every_codec(codec):
    """``units µm`` is one UTF-8 word: every codec writes it (dwt2d once wrote its header as ASCII
    and failed) and decoding gives it back."""
    result = kept_promises(run("encode", *codec, stdin=grid_text([[1, 2, 3, 4]] * 3, extra="units µm")))
    assert result.status == 0 and read_any(result.stdout, "coded").units == "µm"
