"""Conformance of the codec file formats: spec examples, rejections via the CLI, thesis files."""

import math
import warnings

import numpy as np
import pytest

from mzc.codecs.rows import spans
from mzc.codecs.rows import transforms as T
from mzc.codecs.rows.legacy import dwt_kept_mask, read_legacy, thesis_lengths
from mzc.formats import read_any
from mzc.grid import ZGrid

from codec_contract import assert_heights, spec_examples


@pytest.mark.parametrize("data, expected", [pytest.param(d, e, id=i) for d, e, i in spec_examples()])
def test_spec_example_decodes_to_its_expected_grid(data, expected):
    assert_heights(read_any(data, "spec").z, expected)


# --- rejections through the CLI -------------------------------------------------------

GRID_HEADER = "rows 2\ncols 8\nd1 3\nd2 0.25\ndata\n"
DCT = "mzc-dct 1.0\nquality 100\n" + GRID_HEADER
DWT = "mzc-dwt 1.0\nquality 100\nwavelet db1\nlevel 3\n" + GRID_HEADER
GOOD_DCT_ROW = "1 8 4.9497 -3.2212 0 -0.3367 0 -0.1005 0 -0.0254\n"

REJECTIONS = {
    "wrong magic": ("mzc-dcx 1.0\n" + GRID_HEADER, "unknown mzc format"),
    "newer major": (DCT.replace("1.0", "3.0", 1) + GOOD_DCT_ROW * 2, "newer"),
    "truncated rows": (DCT + GOOD_DCT_ROW, "row line"),
    "missing coefficient": (DCT + GOOD_DCT_ROW + "1 8 4.9497 -3.2212 0 -0.3367 0 -0.1005 0\n", "coefficients"),
    "v1 after v2": (DCT + GOOD_DCT_ROW + "5 3 1 2 3\n", "v2"),
    "span outside grid": (DCT + GOOD_DCT_ROW + "1 9 1 2 3 4 5 6 7 8 9\n", "v2"),
    "quality 0": (DCT.replace("quality 100", "quality 0") + GOOD_DCT_ROW * 2, "quality"),
    "quality 101": (DCT.replace("quality 100", "quality 101") + GOOD_DCT_ROW * 2, "quality"),
    "dwt lengths": (DWT + "1 8 1 1 2 4 8 1 2 3 4 5 6 7 8\n" + "1 8 1 1 2 3 8 1 2 3 4 5 6 7 8\n", "lengths"),
    "nan coefficient": (DCT + GOOD_DCT_ROW + GOOD_DCT_ROW.replace("-3.2212", "nan"), "finite"),
    "inf coefficient": (DCT + GOOD_DCT_ROW + GOOD_DCT_ROW.replace("-3.2212", "inf"), "finite"),
    "huge size": (DCT.replace("rows 2", "rows 100000").replace("cols 8", "cols 100000"), "cols"),
    "bad hole run": (DCT + GOOD_DCT_ROW * 2 + "holes 1\n1 1 2\n", "holes"),
    "bad dft L": ("mzc-dft 1.0\nquality 100\n" + GRID_HEADER.replace("rows 2", "rows 1")
                  + "1 8 1 0 2 0 0 0 0\n", "L"),
    "poly count": ("mzc-poly 1.0\nbasis chebyshev\ndegree 2\n" + GRID_HEADER.replace("rows 2", "rows 1")
                   + "1 8 1 2\n", "coefficients"),
}


@pytest.mark.parametrize("name", REJECTIONS)
def test_bad_file_is_one_line_error_and_no_output(mzc, tmp_path, name):
    data, word = REJECTIONS[name]
    output = tmp_path / "out.zg"
    result = mzc("decode", "-o", output, input=data.encode())
    stderr = result.stderr.decode()
    assert result.returncode == 1, stderr
    assert len(stderr.splitlines()) == 1 and stderr.startswith("mzc: <stdin>")
    assert word in stderr and "Traceback" not in stderr
    assert not output.exists()


def test_error_names_the_line(mzc):
    result = mzc("decode", input=(DCT + GOOD_DCT_ROW + "1 8 1 2\n").encode())
    assert result.stderr.decode().startswith("mzc: <stdin>:9: coefficients:")  # line 9: the second row


@pytest.mark.parametrize("arguments", [["--rmse", "1", "--size", "10"], ["--dct", "--dwt"],
                                       ["--dct", "--wavelet", "db2"], ["--poly", "3", "-q", "50"],
                                       ["--dwt", "-q", "0"]])
def test_encode_usage_errors(mzc, tmp_path, arguments):
    output = tmp_path / "out"
    result = mzc("encode", *arguments, "-o", output, input=b"mzc-zgrid 1.0\nrows 1\ncols 1\nd1 1\nd2 1\ndata\n1\n")
    assert result.returncode == 2 and not output.exists()


def test_encode_decode_pipeline(mzc):
    grid = b"mzc-zgrid 1.0\nrows 2\ncols 5\nd1 3\nd2 0.5\ndata\nnan 1 nan 3 4\n1 2 3 4 5\n"
    for codec in (["--dct"], ["--dft"], ["--dwt", "--wavelet", "db2"], ["--poly", "4"]):
        encoded = mzc("encode", *codec, input=grid, check=True).stdout
        decoded = mzc("decode", "--plain", "--precision", "4", input=encoded, check=True).stdout.decode()
        assert decoded.splitlines()[-2:] == ["nan 1 nan 3 4", "1 2 3 4 5"], codec


# --- thesis (legacy) files, written here as the MATLAB code writes them ------------------

def legacy_grid():
    """A grid with ragged spans and an empty row (the MATLAB code cannot code holes)."""
    rng = np.random.default_rng(3)
    z = 20 + np.cumsum(rng.normal(0, 0.3, (5, 40)), axis=1)
    z[0, :4] = z[0, 31:] = np.nan
    z[2, :] = np.nan
    z[3, 38:] = np.nan
    z[4, :39] = np.nan  # one sample: the DFT writer stores no coefficients
    return ZGrid(z, 3.3, 0.3)


def matlab_file(grid, kind, quality):
    """The bytes gmprCompressFFT/DCT/DWT would write for ``grid``."""
    first, last = spans(grid.z)
    d2 = 2 * grid.d2 if kind == "dft" else grid.d2
    lines = [f"{grid.d1:12.4f}\t{d2:12.4f}\t{grid.shape[0]}\t{grid.shape[1]}\t{quality}"]
    for r in range(grid.shape[0]):
        if first[r] < 0:
            lines.append("1\t1\tNaN\t" if kind == "dct" else "0\t0\t")
            continue
        span = grid.z[r, first[r]:last[r] + 1]
        lines.append(f"{first[r] + 1}\t{last[r] + 1}\t" + matlab_row(span, kind, quality))
    return ("\n".join(lines) + "\n").encode()


def matlab_row(span, kind, quality):
    """The numbers after v1 v2 on one MATLAB row line."""
    def numbers(values):
        return "".join(f"{v:12.4f}\t" for v in values)

    if kind == "dct":
        return numbers(T.dct_forward(span)[:math.floor((quality / 100) * span.size)])
    if kind == "dft":
        a0, a_last, an, bn = T.dft_forward(span) if span.size > 2 else (0, 0, np.zeros(0), np.zeros(0))
        count = math.floor((quality / 100) * an.size)
        return f"{a0:12.4f}\t{a_last:12.4f}\t{an.size}\t" + numbers(an[:count]) + numbers(bn[:count])
    import pywt

    lengths = thesis_lengths(span.size)
    with warnings.catch_warnings():  # MATLAB does not cap the level for short spans; neither do we here
        warnings.simplefilter("ignore", UserWarning)
        coefficients = np.concatenate(pywt.wavedec(span, "db1", mode="symmetric", level=3))
    mask = dwt_kept_mask(lengths, quality)
    return "".join(f"{n}\t" for n in lengths) + f"{sum(lengths[:4])}\t" + numbers(coefficients[mask])


@pytest.mark.parametrize("kind", ["dft", "dct", "dwt"])
def test_thesis_file_at_quality_100_decodes(kind):
    grid = legacy_grid()
    decoded = read_legacy(matlab_file(grid, kind, 100), "thesis", kind)
    expected = grid.z.copy()
    if kind == "dft":
        expected[4] = np.nan
    np.testing.assert_array_equal(np.isnan(decoded.z), np.isnan(expected))
    assert np.nanmax(np.abs(decoded.z - expected)) < 2e-3
    assert (decoded.d1, decoded.d2) == (3.3, 0.3)


def test_thesis_dwt_file_drops_the_start_of_each_band():
    import pywt

    grid = legacy_grid()
    decoded = read_legacy(matlab_file(grid, "dwt", 30), "thesis", "dwt").z
    span = grid.z[1]  # 40 samples: C = A3 [0:5] D3 [5:10] D2 [10:20] D1 [20:40]
    coefficients = np.concatenate(pywt.wavedec(span, "db1", mode="symmetric", level=3))
    # D = 35, floor(30*35/100) = 10 kept, 25 dropped: all of D1 and the first 5 of D2.
    coefficients[20:] = 0
    coefficients[10:15] = 0
    np.testing.assert_allclose(decoded[1], T.dwt_inverse(coefficients, thesis_lengths(40)), atol=1e-3)


def test_thesis_quality_uses_matlab_floating_floor():
    assert math.floor((29 / 100) * 100) == 28
    grid = ZGrid(np.arange(100.0)[None, :], 1, 1)
    data = matlab_file(grid, "dct", 29)
    assert len(data.splitlines()[1].split()) == 2 + 28
    read_legacy(data, "thesis", "dct")


def test_thesis_polynomial_file_decodes():
    grid = legacy_grid()
    first, last = spans(grid.z)
    lines = ["k1 5", "k2 40", "D1 3.3", "D2 0.3"]
    for r in range(5):
        if first[r] < 0:
            lines.append("NaN NaN NaN 0 0")
            continue
        x = np.arange(first[r] + 1, last[r] + 2) * 0.3
        degree = min(2, x.size - 1)
        coefficients = np.polyfit(x, grid.z[r, first[r]:last[r] + 1], degree)
        lines.append(" ".join(f"{v:.7e}" for v in [*coefficients, first[r] + 1, last[r] + 1]))
        grid.z[r, first[r]:last[r] + 1] = np.polyval(np.array([float(f"{c:.7e}") for c in coefficients]), x)
    decoded = read_legacy(("\n".join(lines) + "\n").encode(), "thesis", "poly").z
    np.testing.assert_array_equal(np.isnan(decoded), np.isnan(grid.z))
    np.testing.assert_allclose(decoded[~np.isnan(decoded)], grid.z[~np.isnan(grid.z)], atol=1e-6)


def test_legacy_rejections_via_cli(mzc, tmp_path):
    good = matlab_file(legacy_grid(), "dct", 100).decode()
    bad = {
        "header": good.replace("\t5\t40\t100", "\t5\t40"),
        "quality": good.replace("\t5\t40\t100", "\t5\t40\t101"),
        "rows": "\n".join(good.splitlines()[:-1]) + "\n",
    }
    for name, text in bad.items():
        output = tmp_path / "o.zg"
        result = mzc("decode", "--legacy", "dct", "-o", output, input=text.encode())
        stderr = result.stderr.decode()
        assert result.returncode == 1 and len(stderr.splitlines()) == 1, (name, stderr)
        assert "Traceback" not in stderr and not output.exists()
    ok = mzc("decode", "--legacy", "dct", input=good.encode(), check=True)
    assert ok.stdout.startswith(b"mzc-zgrid 3.0")
