"""Colour in the dwt2d 7.0 file (issue 32, spec/dwt2d.md, Colours of 7.0): the colour section
written after the payload of a grid with colours, decoded with the grid, its target in the
options (API and CLI), refused in one line when damaged, and named by ``mzc info``.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from test_colour import analytic_colour, ascii_ply, coloured_surface, textured_obj

import mzc
from mzc.codecs.dwt2d import compact
from mzc.errors import MzcError
from mzc.grid import ZGrid

from conftest import run_mzc


def psnr(decoded, original, valid):
    """PSNR in dB of ``decoded`` against ``original`` colours over the ``valid`` nodes' three channels."""
    error = (decoded.astype(float) - original.astype(float))[valid]
    return 10 * np.log10(255.0 ** 2 / np.mean(error ** 2))


def sliced():
    """The generated coloured height field sliced at 0.1 (about 8000 valid nodes)."""
    from mzc.ops.slicing import slice_surface

    return slice_surface(coloured_surface(), d1=0.1, align="pca")


def test_the_cli_pipeline_keeps_colours_within_the_psnr_target(tmp_path):
    """mzc slice col.ply | mzc encode --colour-psnr 36 | mzc decode | mzc triangulate -o out.ply:
    the decoded grid's colours meet 36 dB against the sliced ones, the rebuilt mesh's vertices
    carry them, within a few levels of the surface's own colour; --colour-max-error 3 bounds
    every node."""
    from mzc.formats import read_any
    from mzc.meshes import read_mesh

    (tmp_path / "col.ply").write_bytes(ascii_ply(coloured_surface()))
    grid = run_mzc("slice", tmp_path / "col.ply", "--d1", "0.1", "--align", "pca", check=True).stdout
    original = read_any(grid, "col.zg")
    encoded = run_mzc("encode", "--colour-psnr", "36", input=grid, check=True)
    assert encoded.stderr == b""
    decoded = run_mzc("decode", input=encoded.stdout, check=True).stdout
    coloured = read_any(decoded, "decoded.zg")
    assert decoded.startswith(b"mzc-zgrid 5.") and 36 <= psnr(coloured.colors, original.colors, original.valid) < 45
    run_mzc("triangulate", "--vertices", "all", "-o", tmp_path / "out.ply", input=decoded, check=True)
    out = read_mesh(tmp_path / "out.ply")
    errors = out.colors - analytic_colour(out.points[:, 0], out.points[:, 1])
    assert len(out.points) == original.valid.sum() and np.sqrt(np.mean(errors ** 2)) < 4.5
    bounded = run_mzc("encode", "--colour-max-error", "3", input=grid, check=True).stdout
    colours = read_any(bounded, "bounded.mzw2").colors.astype(int)
    assert np.abs(colours - original.colors)[original.valid].max() <= 3 and len(bounded) > len(encoded.stdout)


def test_the_api_takes_the_colour_targets_and_defaults_to_36_db():
    """mzc.encode(grid, "dwt2d", colour_psnr=...) or colour_max_error=...; neither: 36 dB; both, or
    one out of range, an MzcError naming them (the CLI spells them as flags, below)."""
    grid = sliced()
    default = mzc.encode(grid, "dwt2d")
    assert compact.read(default, "t")[0].tokens("colour_psnr") == ["36"]
    assert default == mzc.encode(grid, "dwt2d", colour_psnr=36)
    assert 36 <= psnr(mzc.decode(default).colors, grid.colors, grid.valid)
    coarse = mzc.encode(grid, "dwt2d", colour_psnr=28)
    assert len(coarse) < len(default) and 28 <= psnr(mzc.decode(coarse).colors, grid.colors, grid.valid) < 36
    lossless = mzc.encode(grid, "dwt2d", colour_max_error=0)
    assert mzc.decode(lossless).colors.tobytes() == grid.colors.tobytes()
    with pytest.raises(MzcError, match="colour_psnr or colour_max_error, not both") as error:
        mzc.encode(grid, "dwt2d", colour_psnr=30, colour_max_error=2)
    assert error.value.options == ("colour_psnr", "colour_max_error")
    for bad in ({"colour_psnr": 0}, {"colour_psnr": 250}, {"colour_max_error": 128}, {"colour_max_error": 1.5}):
        with pytest.raises(MzcError) as error:
            mzc.encode(grid, "dwt2d", **bad)
        assert error.value.field == next(iter(bad))


@pytest.mark.parametrize("flags, said", [
    (["--colour-psnr", "30", "--colour-max-error", "2"], "give one of --colour-psnr or --colour-max-error, not both"),
    (["--colour-psnr", "-1"], "--colour-psnr: -1.0 must be > 0 and <= 200"),
    (["--colour-max-error", "200"], "--colour-max-error"),
])
def test_the_cli_refuses_bad_colour_targets_in_one_line(tmp_path, flags, said):
    from mzc.formats import zgrid

    (tmp_path / "c.zg").write_bytes(zgrid.write(sliced(), raw="float64"))
    result = run_mzc("encode", *flags, tmp_path / "c.zg", "-o", tmp_path / "c.mzw2")
    lines = result.stderr.decode().strip().splitlines()
    assert result.returncode != 0 and len(lines) == 1 and said in lines[0], lines
    assert not (tmp_path / "c.mzw2").exists()


@st.composite
def coloured_grids(draw):
    """Small planar grids with holes (at least one valid node) and any colours."""
    shape = draw(st.tuples(st.integers(1, 12), st.integers(1, 12)))
    z = draw(arrays(float, shape, elements=st.floats(-100, 100, allow_nan=False)))
    holes = draw(arrays(bool, shape))
    holes.flat[draw(st.integers(0, z.size - 1))] = False
    z[holes] = np.nan
    return ZGrid(z, 0.5, 0.5, units="mm", colors=draw(arrays(np.uint8, (*shape, 3))))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(coloured_grids(), st.integers(0, 12))
def test_a_coloured_grid_round_trips_through_the_7_0_file_within_its_bounds(grid, bound):
    """Heights within max_error, colours within colour_max_error at every valid node (0 at the
    others), the same file from the decoded grid's colours' own encoding target; the colour
    section is section 3, the last."""
    data = mzc.encode(grid, "dwt2d", max_error=0.01, colour_max_error=bound)
    back = mzc.decode(data)
    valid = grid.valid
    assert np.abs(back.z - grid.z)[valid].max() <= 0.01 + 1e-9
    assert np.abs(back.colors.astype(int) - grid.colors)[valid].max() <= bound
    assert not back.colors[~valid].any()
    header, _payload, colour = compact.read(data, "t")
    assert header.tokens("colour_max_error") == [str(bound)] and data.endswith(colour + data[-4:])


def coloured_file():
    """An 8.0 file of a small coloured grid (7.0's colour section; 10.0's is checked in test_dwt2d_tight), and
    where its colour section (tag, length, body, CRC) starts."""
    from mzc.codecs import dwt2d

    grid = sliced()
    data = dwt2d.encode_whole(grid, max_error=0.05, colour_psnr=30, compact=dwt2d.FLIPS_VERSION)[0]
    colour = compact.read(data, "t")[2]
    start = len(data) - 4 - len(colour) - len(compact.varint(len(colour))) - 1
    assert data[start] == compact.COLOUR
    return data, start


def resectioned(data, start, body):
    """``data`` with its colour section's body replaced by ``body``, the section's CRC-32 made to fit
    (so the colour section's own checks are what refuse it)."""
    return data[:start] + compact.section(compact.COLOUR, body)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(st.data())
def test_a_damaged_colour_section_is_refused_in_one_line(data):
    """A byte changed (the section's CRC-32 catches it), a body changed under a fitting section CRC
    (the colour section's own header and CRC-32), cut short, or bytes added: an MzcError, never a
    grid without its colours or with others."""
    good, start = coloured_file()
    body = compact.read(good, "t")[2]
    at = data.draw(st.integers(start, len(good) - 1))
    flipped = good[:at] + bytes([good[at] ^ data.draw(st.integers(1, 255))]) + good[at + 1:]
    inner = data.draw(st.integers(0, len(body) - 1))
    bad_body = body[:inner] + bytes([body[inner] ^ 0x5A]) + body[inner + 1:]
    cut = data.draw(st.integers(1, len(good) - start - 1))
    for bad in (flipped, resectioned(good, start, bad_body), resectioned(good, start, body[:-cut]),
                good[:-cut], good + b"\x03\x00"):
        with pytest.raises(MzcError) as error:
            mzc.decode(bad)
        assert "\n" not in str(error.value)


def test_the_cli_refuses_a_damaged_colour_section_in_one_line_and_writes_nothing(tmp_path):
    good, start = coloured_file()
    body = compact.read(good, "t")[2]
    (tmp_path / "bad.mzw2").write_bytes(resectioned(good, start, body[:20] + b"\xff" + body[21:]))
    result = run_mzc("decode", tmp_path / "bad.mzw2", "-o", tmp_path / "out.zg")
    lines = result.stderr.decode().strip().splitlines()
    assert result.returncode != 0 and len(lines) == 1 and "colour" in lines[0] and "Traceback" not in lines[0]
    assert not (tmp_path / "out.zg").exists()


def test_info_shows_the_colour_sections_bytes_and_target(tmp_path):
    good, start = coloured_file()
    (tmp_path / "c.mzw2").write_bytes(good)
    out = run_mzc("info", tmp_path / "c.mzw2", check=True).stdout.decode()
    body = compact.read(good, "t")[2]
    assert f"colour    {len(body)} bytes (section 3), colour_psnr 30" in out and "  colour_psnr 30" in out
    plain = mzc.encode(ZGrid(np.ones((4, 4)), 1.0, 1.0), "dwt2d", max_error=0.1)
    (tmp_path / "p.mzw2").write_bytes(plain)
    assert "\ncolour " not in run_mzc("info", tmp_path / "p.mzw2", check=True).stdout.decode()


def test_batch_encode_names_the_colours_a_file_drops(tmp_path):
    """One item of mzc batch encode records the warning of colours its file does not carry (here: a
    row codec's) in its manifest row, and none for a dwt2d file, whole or in tiles (which keep them)."""
    from mzc.batch import Job, items, work

    source = tmp_path / "col.ply"
    source.write_bytes(ascii_ply(coloured_surface()))
    for name, codec, options, warned in (("dct", "dct", {"quality": 20}, True), ("whole", "dwt2d", {}, False),
                                         ("tiles", "dwt2d", {"tile": 16}, False)):
        settings = {"codec": codec, "codec_options": {**({"max_error": 0.05} if codec == "dwt2d" else {}), **options},
                    "slice_options": {"d1": 0.1, "align": "pca"}}
        row = work.run_item(Job("encode", str(tmp_path), settings), items.Item(str(source), f"{name}.mzc"))
        assert row["status"] == "ok" and ("the nodes' colours" in row["warning"]) == warned, row
        assert (mzc.decode((tmp_path / f"{name}.mzc").read_bytes()).colors is None) == warned


def test_the_benchmarks_colour_error_is_the_surface_colour_at_the_nearest_point():
    """benchmarks/coloured_scans.py's colour error: 0 (infinite PSNR) for the source's own vertices,
    3 levels RMS (38.59 dB) for colours 3 levels off, and on a triangle's interior the mix of its
    corners' colours, not the nearest vertex's."""
    import sys

    from conftest import REPO

    sys.path.insert(0, str(REPO / "benchmarks"))
    from coloured_scans import colour_errors

    mesh = coloured_surface()
    assert colour_errors(mesh, mesh.points, mesh.colors) == (0.0, float("inf"))
    rms, peak = colour_errors(mesh, mesh.points, mesh.colors.astype(int) + 3)
    assert rms == pytest.approx(3.0) and peak == pytest.approx(10 * np.log10(255.0 ** 2 / 9))
    corners = mesh.triangles[100]
    centre = mesh.points[corners].mean(axis=0, keepdims=True)
    mixed = np.round(mesh.colors[corners].astype(float).mean(axis=0, keepdims=True))
    assert colour_errors(mesh, centre, mixed)[0] < 0.5


def test_a_map_kd_name_with_spaces_is_read_whole(tmp_path):
    """``map_Kd fuze uv.jpg`` (trimesh's fuze bottle) names one file with a space in it: the texture
    is read, with no warning; after options the name is still the last word."""
    import warnings

    from mzc.errors import MzcWarning
    from mzc.meshes import read_mesh

    path = textured_obj(tmp_path, image_name="skin tone.png")
    (tmp_path / "face.mtl").write_text("newmtl skin\nKd 1 1 1\nmap_Kd skin tone.png\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", MzcWarning)
        mesh = read_mesh(path)
    errors = mesh.colors - analytic_colour(mesh.points[:, 0], mesh.points[:, 1])
    assert np.abs(errors).max() <= 4


def test_a_window_of_a_coloured_file_keeps_its_colours():
    """mzc.decode(data, window=...) of a 7.0 file with colours: the window's heights and colours."""
    grid = sliced()
    data = mzc.encode(grid, "dwt2d", max_error=0.05, colour_max_error=0)
    whole, part = mzc.decode(data), mzc.decode(data, window=(3, 5, 10, 12))
    assert part.colors.tobytes() == whole.colors[3:13, 5:17].tobytes()
    np.testing.assert_array_equal(part.z, whole.z[3:13, 5:17])
