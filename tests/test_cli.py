"""Command-line conventions: help, errors on one line, atomic output, the pipeline as subprocesses."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mzc.formats import zgrid

from codec_contract import header_fields
from conftest import face_path, run_mzc


def test_help_lists_every_command_without_importing_numerics():
    result = subprocess.run([sys.executable, "-X", "importtime", "-m", "mzc", "--help"],
                            capture_output=True, text=True, check=True)
    for name in ("slice", "encode", "decode", "densify", "triangulate", "diff", "info", "sample"):
        assert f"\n  {name} " in result.stdout
    imported = {line.split("|")[-1].strip() for line in result.stderr.splitlines()}
    assert not imported & {"numpy", "scipy", "meshio", "matplotlib", "pywt"}


def test_the_formats_the_options_offer_are_the_ones_mzc_writes():
    from mzc.cli.options import RASTER_FORMATS
    from mzc.cli.triangulate import FORMATS
    from mzc.formats import SURFACES, writable

    assert (set(RASTER_FORMATS), set(FORMATS)) == (set(writable(("raster",))), set(writable(SURFACES)))


def test_version(mzc):
    assert mzc("--version", check=True).stdout.decode().startswith("mzc, version ")


def assert_one_line_error(result, *fragments):
    err = result.stderr.decode()
    assert result.returncode == 1, err
    assert err.startswith("mzc: ") and err.count("\n") == 1 and "Traceback" not in err
    for fragment in fragments:
        assert fragment in err
    assert result.stdout == b""


def test_missing_file_is_one_line(mzc):
    assert_one_line_error(mzc("triangulate", "nope.zg"), "nope.zg", "no such file")


def test_a_mesh_given_where_a_grid_is_expected(mzc, tmp_path):
    mesh = tmp_path / "m.obj"
    mesh.write_text("v 0 0 0\n")
    assert_one_line_error(mzc("triangulate", mesh), "m.obj: holds a mesh (obj), not a z-grid")


def test_bad_grid_names_file_and_line(mzc, tmp_path):
    bad = tmp_path / "bad.zg"
    bad.write_bytes(b"mzc-zgrid 1.0\nrows 2\ncols 2\nd1 1\nd2 1\ndata\n1 2\n3 oops\n")
    assert_one_line_error(mzc("info", "--decode", bad), "bad.zg:8", "oops")
    assert mzc("info", bad).returncode == 0   # without --decode, info reads the header alone


def test_encode_imports_only_what_its_codec_uses(tmp_path):
    """mzc encode builds its options from every codec; --dct must not load dwt2d's entropy coder."""
    grid = tmp_path / "g.zg"
    grid.write_bytes(b"mzc-zgrid 1.0\nrows 2\ncols 2\nd1 1\nd2 1\ndata\n1 2\n3 4\n")
    result = subprocess.run([sys.executable, "-X", "importtime", "-m", "mzc", "encode", "--dct", str(grid)],
                            capture_output=True, text=True)
    imported = {line.split("|")[-1].strip() for line in result.stderr.splitlines()}
    assert result.returncode == 0 and not imported & {"constriction", "numba", "pywt", "meshio", "matplotlib"}


HEAVY = {"scipy", "constriction", "numba", "llvmlite", "pywt", "meshio", "matplotlib", "distributed", "dask",
         "laspy", "lazrs", "rasterio"}
# what each command may load of HEAVY: scipy only where a sparse solve, an FFT or a KD-tree runs, constriction only
# to encode dwt2d (its decoder is a small C extension; numba, which it once used, cost 0.8 s of start-up),
# laspy and lazrs only to read a LAS/LAZ, rasterio only to read or write a GeoTIFF
IMPORT_SETS = [
    (["slice", "{mesh}"], set()),
    (["slice", "{laz}"], {"laspy", "lazrs", "scipy"}),   # a cloud: Delaunay (scipy.spatial)
    (["slice", "{pcd}"], {"scipy"}),
    (["encode", "--dwt2d", "--rmse", "0.05", "{grid}"], {"constriction"}),
    (["encode", "--dct", "-q", "20", "{grid}"], {"scipy"}),                             # scipy.fft
    (["decode", "{coded}"], set()),
    (["densify", "-n", "1", "{grid}"], set()),                                          # the biharmonic solve: C
    (["triangulate", "{grid}"], set()),
    (["triangulate", "{grid}", "-o", "{grid}.ply"], set()),                             # our own PLY writer
    (["info", "{coded}"], set()),
    (["diff", "{grid}", "{grid}"], set()),
    (["slice", "{tif}"], {"rasterio"}),                                                 # GeoTIFF: GDAL
    (["slice", "{asc}"], set()),                                                        # an ESRI grid: our own
    (["decode", "{grid}", "--format", "tif"], {"rasterio"}),
    (["decode", "{grid}", "--format", "asc"], set()),
    (["diff", "{mesh}", "{grid}", "--surface"], set()),                                 # the C distance search
    (["diff", "{mesh}", "{grid}", "--heightfield"], {"scipy"}),                         # KD-trees (front_most)
]


@pytest.fixture(scope="module")
def sample_files(tmp_path_factory):
    """A sample mesh, its grid and its dwt2d file, and public LAZ and PCD clouds."""
    folder = tmp_path_factory.mktemp("imports")
    mesh, grid, coded = folder / "bump.obj", folder / "bump.zg", folder / "bump.mzw2"
    subprocess.run([sys.executable, "-m", "mzc", "sample", "bump", "-o", mesh], check=True)
    subprocess.run([sys.executable, "-m", "mzc", "slice", mesh, "-o", grid], check=True)
    subprocess.run([sys.executable, "-m", "mzc", "encode", "--dwt2d", "--rmse", "0.05", grid, "-o", coded], check=True)
    public = Path(__file__).resolve().parent / "data" / "public"
    return {"mesh": mesh, "grid": grid, "coded": coded, "laz": public / "simple.laz", "pcd": public / "milk.pcd",
            "tif": public / "srtm_blurred_res.tif", "asc": public / "hugo_site.asc"}


@pytest.mark.parametrize("arguments, allowed", IMPORT_SETS, ids=lambda v: " ".join(v) if isinstance(v, list) else "")
def test_each_command_imports_only_what_it_uses(sample_files, arguments, allowed):
    arguments = [a.format(**sample_files) for a in arguments]
    result = subprocess.run([sys.executable, "-X", "importtime", "-m", "mzc", *arguments],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert result.returncode == 0, result.stderr[-500:]
    imported = {line.split("|")[-1].strip().split(".")[0] for line in result.stderr.splitlines() if "|" in line}
    assert imported & HEAVY <= allowed


def test_usage_errors_exit_2(mzc):
    result = mzc("diff", "only-one")
    assert result.returncode == 2 and "Traceback" not in result.stderr.decode()


@pytest.mark.parametrize("arguments, problem", [
    (["encode", "--dwt", "--level", "0"], "mzc encode: --level: 0 is outside 1..32"),
    (["diff", "only-one"], "mzc diff: Missing argument 'B'."),
    (["densify", "-n", "x"], "mzc densify: -n: 'x' is not a valid integer"),
    (["nonsense"], "mzc: No such command 'nonsense'."),
])
def test_a_usage_error_is_one_line_that_starts_with_the_problem(mzc, arguments, problem):
    result = mzc(*arguments, input=b"")
    lines = result.stderr.decode().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and lines[0].startswith(problem), lines
    assert lines[0].endswith("--help')")


def test_failure_leaves_an_existing_output_untouched_and_no_temp_files(mzc, tmp_path):
    out = tmp_path / "out.obj"
    out.write_text("precious")
    result = mzc("triangulate", "-o", out, input=b"mzc-zgrid 1.0\nrows 5\ncols 1\nd1 1\nd2 1\ndata\n1\n")
    assert_one_line_error(result, "header says rows 5")
    assert out.read_text() == "precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.obj"]


def test_output_over_the_input_is_refused(mzc, tmp_path):
    grid = tmp_path / "g.zg"
    grid.write_bytes(b"mzc-zgrid 1.0\nrows 2\ncols 2\nd1 1\nd2 1\ndata\n1 2\n3 4\n")
    before = grid.read_bytes()
    assert_one_line_error(mzc("densify", grid, "-n", "1", "-o", grid), "overwrite an input")
    assert grid.read_bytes() == before


def test_sample_slice_triangulate_diff_pipeline(mzc, tmp_path):
    mesh = tmp_path / "bump.obj"
    mzc("sample", "bump", "-o", mesh, check=True)
    grid = mzc("slice", mesh, "--d1", "1", "--d2", "1", check=True).stdout
    assert grid.startswith(b"mzc-zgrid 3.2\n")   # the raw body, the pipes' default (3.2: the bump's vertex count)
    rebuilt = tmp_path / "rebuilt.ply"
    mzc("triangulate", "-o", rebuilt, input=grid, check=True)
    report = json.loads(mzc("diff", mesh, rebuilt, "--json", check=True).stdout)
    assert report["grid_count"] > 10_000
    # A 1 mm slice of a smooth bump, rebuilt linearly, stays within a few hundredths of a mm.
    assert report["grid_p50"] < 0.01 and report["grid_p95"] < 0.05


def test_info_describes_a_grid(mzc, tmp_path):
    grid = mzc("slice", "-", input=mzc("sample", "bump", check=True).stdout)
    if grid.returncode != 0:  # slicing a mesh from stdin is allowed to be unsupported
        mesh = tmp_path / "b.obj"
        mzc("sample", "bump", "-o", mesh, check=True)
        grid = mzc("slice", mesh, check=True)
    text = mzc("info", "--decode", input=grid.stdout, check=True).stdout.decode()
    assert "format    mzc-zgrid 3.2" in text and "rows x" in text and "valid" in text
    assert "source    " in text and " vertices (triangulate's default size)" in text
    assert "  raw float64\n" in text
    assert f"bytes     {len(grid.stdout)}" in text


def test_face_round_trip_meets_the_issue_targets(mzc, tmp_path):
    face = face_path("f18.ply")
    grid = mzc("slice", face, "--d1", "0.5", "--d2", "0.5", check=True).stdout
    out = tmp_path / "out.ply"
    mzc("triangulate", "-o", out, input=grid, check=True)
    report = json.loads(mzc("diff", face, out, "--json", check=True).stdout)
    assert report["grid_p50"] < 0.01 and report["grid_p95"] < 0.1, report


def test_diff_surface_distance_of_a_face_against_itself_is_zero(mzc):
    face = face_path("f18.ply")
    report = json.loads(mzc("diff", face, face, "--surface", "--samples", "20000", "--json", check=True).stdout)
    assert report["grid_rmse"] == 0 and report["surface_rms"] < 1e-9


def test_error_grid_is_a_zgrid_of_b_minus_a(mzc, tmp_path):
    a, b = tmp_path / "a.zg", tmp_path / "b.zg"
    a.write_bytes(b"mzc-zgrid 1.0\nrows 2\ncols 2\nd1 1\nd2 1\ndata\n1 2\n3 4\n")
    b.write_bytes(b"mzc-zgrid 1.0\nrows 2\ncols 2\nd1 1\nd2 1\ndata\n1.5 2\n3 nan\n")
    errors = tmp_path / "e.zg"
    report = json.loads(mzc("diff", a, b, "--json", "--error-grid", errors, check=True).stdout)
    assert report["grid_count"] == 3 and report["grid_max"] == pytest.approx(0.5)
    np.testing.assert_array_equal(zgrid.read(errors.read_bytes(), "e.zg").z, [[0.5, 0], [0, np.nan]])
    mzc("diff", a, b, "--plain", "--error-grid", errors, check=True)
    assert errors.read_text().endswith("data\n0.5 0\n0 nan\n")


def test_encode_dwt2d_holds_its_max_error_through_the_cli(mzc, tmp_path):
    mesh = tmp_path / "bump.obj"
    mzc("sample", "bump", "-o", mesh, check=True)
    grid = tmp_path / "bump.zg"
    mzc("slice", mesh, "--d1", "1", "--d2", "1", "-o", grid, check=True)
    packed = mzc("encode", "--dwt2d", "--max-error", "0.02", grid, check=True).stdout
    assert packed.startswith(b"mzc-dwt2d 10.1\n") and len(packed) < grid.stat().st_size / 10   # band models pay here
    decoded = tmp_path / "back.zg"
    mzc("decode", "-o", decoded, input=packed, check=True)
    report = json.loads(mzc("diff", grid, decoded, "--json", check=True).stdout)
    assert report["grid_max"] <= 0.02
    flat = mzc("encode", "--dwt2d", "--rmse", "0.02", "--slope-limit", "1", grid, check=True).stdout
    assert header_fields(flat)["slope_limit"] == ["1"]
    assert b"slope_limit" not in mzc("encode", "--dwt2d", "--rmse", "0.02", grid).stdout   # the default, 2


@pytest.mark.parametrize("options", [["--max-error", "1", "--size", "100"],
                                     ["--dwt2d", "--max-error", "1", "--rmse", "1"], ["--dct", "--max-error", "1"],
                                     ["--dct", "--dwt2d", "--size", "100"], ["--dct", "--slope-limit", "2"],
                                     ["--dwt2d", "--rmse", "1", "--slope-limit", "0.5"]])
def test_encode_codec_option_mistakes_are_usage_errors(mzc, options):
    result = mzc("encode", *options, input=b"mzc-zgrid 1.0\nrows 1\ncols 2\nd1 1\nd2 1\ndata\n1 2\n")
    assert result.returncode == 2 and result.stdout == b"" and "Traceback" not in result.stderr.decode()


def test_encode_without_options_is_dwt2d_at_a_tenth_of_the_spacing(mzc, tmp_path):
    import mzc as api

    grid_file = tmp_path / "f18.zg"
    mzc("slice", face_path("f18.ply"), "-o", grid_file, check=True)
    grid = zgrid.read(grid_file.read_bytes(), "f18.zg")
    plain = mzc("encode", grid_file, check=True).stdout
    spacing = min(grid.d1, grid.d2)
    assert plain == mzc("encode", "--dwt2d", "--rmse", repr(spacing / 10), grid_file, check=True).stdout
    assert plain == api.encode(grid) and plain.startswith(b"mzc-dwt2d ")
    decoded = api.decode(plain)
    assert 0 < np.sqrt(np.nanmean((decoded.z - grid.z) ** 2)) < spacing / 5   # node-line RMS, about the target


def test_cli_errors_name_the_options_as_the_cli_spells_them(mzc):
    grid = b"mzc-zgrid 1.0\nrows 1\ncols 2\nd1 1\nd2 1\ndata\n1 2\n"
    both = mzc("encode", "--rmse", "1", "--max-error", "2", input=grid).stderr.decode()
    assert "--max-error, --rmse or --size" in both and "max_error" not in both
    # an option refused below the command, in the library's spelling, comes out as the command's flag
    text = mzc("decode", "--format", "asc", "--float32", input=grid).stderr.decode()
    assert text.endswith("--float32: an ESRI ASCII grid is text: --float32 is for GeoTIFF samples\n")
    help_text = mzc("--help", check=True).stdout.decode()
    assert "encode --dwt2d" in help_text and "--dwt -q" not in help_text


def test_a_long_step_shows_its_progress_on_a_terminal_and_only_there(tmp_path):
    """A step past mzc.progress.DELAY (2 s) draws one redrawn line on a terminal's stderr, cleared
    when it ends; stdout carries the data alone, and a pipe gets no progress at all."""
    import pty

    mesh = tmp_path / "blob.obj"
    run_mzc("sample", "blob", "-o", mesh, check=True)
    command = [sys.executable, "-m", "mzc", "diff", str(mesh), str(mesh), "--samples", "2000000", "--json"]
    leader, follower = pty.openpty()
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=follower)
    os.close(follower)
    drawn = b""
    while chunk := read_terminal(leader):
        drawn += chunk
    os.close(leader)
    report = json.loads(process.stdout.read())
    assert process.wait() == 0 and report["surface_samples"] == 4_000_000
    assert b"mzc: " + str(mesh).encode() + b" vs " in drawn
    assert b"comparing them (2000000 samples per surface)... " in drawn
    assert drawn.endswith(b"\r\x1b[K")   # cleared at the end
    assert run_mzc(*command[3:6], "--samples", "2000000").stderr == b""   # not a terminal: nothing


def read_terminal(fd):
    """The next bytes a pseudo-terminal's other side wrote, b"" once it is closed."""
    try:
        return os.read(fd, 4096)
    except OSError:   # Linux: EIO when the last writer has gone
        return b""


def test_output_files_follow_the_umask(mzc, tmp_path):
    out = tmp_path / "bump.obj"
    mask = os.umask(0o022)
    try:
        mzc("sample", "bump", "-o", out, check=True)
    finally:
        os.umask(mask)
    assert out.stat().st_mode & 0o777 == 0o644


# --- the z-grid's body: raw through pipes, --plain for people -----------------------------


@pytest.fixture
def bump_grid(mzc, tmp_path):
    """A small z-grid of the bump sample, sliced through the command line (raw)."""
    mesh = tmp_path / "bump.obj"
    mzc("sample", "bump", "-o", mesh, check=True)
    return mzc("slice", mesh, "--d1", "2", "--d2", "2", check=True).stdout


def test_filters_write_raw_by_default_and_plain_text_with_plain(mzc, bump_grid):
    grid = zgrid.read(bump_grid, "-")
    assert bump_grid.startswith(b"mzc-zgrid 3.2\n") and b"\nraw float64\ncrc32 " in bump_grid
    assert len(bump_grid.split(b"\ndata\n", 1)[1]) == 8 * grid.z.size
    for command in (["decode"], ["densify", "-n", "0"]):
        assert mzc(*command, input=bump_grid, check=True).stdout == bump_grid   # exact, unchanged
        plain = mzc(*command, "--plain", input=bump_grid, check=True).stdout
        assert plain == zgrid.write(grid)   # today's text, byte for byte
        assert plain.startswith(b"mzc-zgrid 1.2\n") and b"raw" not in plain


def test_float32_halves_the_body_and_every_reader_takes_it(mzc, bump_grid):
    small = mzc("decode", "--float32", input=bump_grid, check=True).stdout
    z = zgrid.read(bump_grid, "-").z
    assert b"\nraw float32\n" in small and len(small.split(b"\ndata\n", 1)[1]) == 4 * z.size
    np.testing.assert_array_equal(zgrid.read(small, "-").z, z.astype(np.float32).astype(float))
    assert b"format    mzc-zgrid 3.2" in mzc("info", input=small, check=True).stdout
    assert mzc("encode", "--dwt2d", "--max-error", "0.05", input=small, check=True).stdout.startswith(b"mzc-dwt2d")


@pytest.mark.parametrize("options, message", [(["--precision", "3"], "--precision rounds the text of --plain"),
                                              (["--plain", "--float32"], "give one")])
def test_body_options_that_contradict_each_other_are_usage_errors(mzc, bump_grid, options, message):
    result = mzc("decode", *options, input=bump_grid)
    assert result.returncode == 2 and message in result.stderr.decode()
    assert result.stdout == b""


def run_on_terminal(arguments):
    """(exit status, what reached the terminal, stderr) of ``mzc ARGUMENTS`` with stdout a pseudo-terminal."""
    import pty

    leader, follower = pty.openpty()
    process = subprocess.Popen([sys.executable, "-m", "mzc", *map(str, arguments)], stdout=follower,
                               stderr=subprocess.PIPE)
    os.close(follower)
    shown = b""
    try:
        while chunk := os.read(leader, 1 << 16):
            shown += chunk
    except OSError:   # EIO: the program closed the terminal's other end and everything is read
        pass
    finally:
        os.close(leader)
    error = process.stderr.read().decode()
    return process.wait(timeout=120), shown, error


def test_a_terminal_gets_text_and_no_compressed_bytes(sample_files):
    """On a terminal, a z-grid comes as the text of --plain (raw is for pipes and files), and
    encode refuses to print compressed bytes, as gzip does; --float32 asked for raw still gets it."""
    status, shown, _ = run_on_terminal(["decode", sample_files["coded"]])
    text = shown.replace(b"\r\n", b"\n").decode("ascii")   # a terminal shows each newline as CR LF
    assert status == 0 and text.startswith("mzc-zgrid 1.2\n") and "\nraw " not in text
    assert zgrid.read(text.encode(), "terminal").z.shape == zgrid.read(
        subprocess.run([sys.executable, "-m", "mzc", "decode", sample_files["coded"]], capture_output=True,
                       check=True).stdout, "pipe").z.shape
    status, shown, _ = run_on_terminal(["decode", sample_files["coded"], "--float32"])
    assert status == 0 and shown.startswith(b"mzc-zgrid 3.2")
    status, shown, error = run_on_terminal(["encode", "--dwt2d", "--rmse", "0.05", sample_files["grid"]])
    assert status == 1 and shown == b""
    assert error == "mzc: <stdout>: compressed data is not written to a terminal: redirect it or give -o FILE\n"
