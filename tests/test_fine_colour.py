"""Colour finer than the nodes (issue 32: slice --colour-scale K): the sample lattice and its mask
(of one grid, and of a multi-chart grid, whose charts each hold their block), the z-grid 6.0 and
the colour sections of version 2 and 3 that carry it, and the pipeline slice | encode --dwt2d |
decode | triangulate --texture on VTK's fran, whose texture comes back finer and closer to the
source than at the nodes alone.
"""

import zlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from mzc.codecs.dwt2d import colour
from mzc.errors import MzcError
from mzc.formats import zgrid
from mzc.grid import ZGrid, fine_mask

from codec_contract import rechecksummed
from conftest import run_mzc

FRAN = __import__("pathlib").Path(__file__).resolve().parent / "data" / "public" / "fran" / "fran.obj"


def fran():
    """The path of VTK's fran (a textured OBJ), skipping the test when it is absent."""
    if not FRAN.is_file():
        pytest.skip("tests/data/public/fran is absent")
    return FRAN


@st.composite
def fine_grids(draw):
    """Small grids with holes and colours sampled 1..4 times finer (any bytes, those of invalid
    samples too: the grid makes them 0)."""
    shape = draw(st.tuples(st.integers(1, 8), st.integers(1, 8)))
    scale = draw(st.integers(1, 4))
    z = draw(arrays(float, shape, elements=st.floats(-1e6, 1e6, allow_nan=False, width=32)))
    z[draw(arrays(bool, shape))] = np.nan
    fine = draw(arrays(np.uint8, ((shape[0] - 1) * scale + 1, (shape[1] - 1) * scale + 1, 3)))
    return ZGrid(z, 0.5, 0.25, units="mm", fine_colors=fine), scale


def brute_fine_mask(valid, scale, label=None):
    """The sample mask by its definition, one sample at a time: every node of the rows and columns
    floor(a / K), ceil(a / K) and floor(b / K), ceil(b / K) valid, and with a chart ``label`` for
    each node, of one chart."""
    rows, cols = ((n - 1) * scale + 1 for n in valid.shape)
    label = np.zeros(valid.shape, dtype=int) if label is None else label

    def valid_sample(a, b):
        nodes = [(r, c) for r in {a // scale, -(-a // scale)} for c in {b // scale, -(-b // scale)}]
        return all(valid[node] for node in nodes) and len({label[node] for node in nodes}) == 1

    return np.array([[valid_sample(a, b) for b in range(cols)] for a in range(rows)], dtype=bool).reshape(rows, cols)


@st.composite
def side_by_side_charts(draw, shape):
    """Charts that tile a grid of ``shape`` in blocks: its columns cut at some places, each piece's
    rows at others (views and lattice offsets any: the mask reads the blocks alone)."""
    from mzc.grid import Chart

    rows, cols = shape
    cuts = sorted(draw(st.sets(st.integers(1, cols - 1), max_size=3))) if cols > 1 else []
    charts = []
    for col0, col1 in zip([0, *cuts], [*cuts, cols]):
        row_cuts = sorted(draw(st.sets(st.integers(1, rows - 1), max_size=2))) if rows > 1 else []
        charts += [Chart(draw(st.sampled_from(["+x", "-y", "+z"])), row0, col0, row1 - row0, col1 - col0, 0, 0)
                   for row0, row1 in zip([0, *row_cuts], [*row_cuts, rows])]
    return tuple(charts)


@settings(max_examples=100, deadline=None)
@given(arrays(bool, st.tuples(st.integers(1, 7), st.integers(1, 7))), st.integers(1, 5), st.data())
def test_the_sample_mask_is_every_node_of_the_samples_cell_in_one_chart(valid, scale, data):
    from mzc.grid import chart_labels

    mask = fine_mask(valid, scale)
    assert mask.tolist() == brute_fine_mask(valid, scale).tolist()
    assert mask[::scale, ::scale].tolist() == valid.tolist()   # a node's sample is valid with it
    charts = data.draw(side_by_side_charts(valid.shape))
    charted = fine_mask(valid, scale, charts)
    assert charted.tolist() == brute_fine_mask(valid, scale, chart_labels(valid.shape, charts)).tolist()
    assert charted[::scale, ::scale].tolist() == valid.tolist()
    if len(charts) == 1:
        assert charted.tolist() == mask.tolist()


@settings(max_examples=150, deadline=None)
@given(fine_grids())
def test_fine_colours_round_trip_exactly_through_the_zgrid(case):
    grid, scale = case
    data = zgrid.write(grid, raw="float64")
    scaled = grid.colour_scale > 1
    assert data.startswith(b"mzc-zgrid 6.0\n" if scaled else b"mzc-zgrid 5.0\n")
    assert scaled == (scale > 1 and grid.shape != (1, 1))
    back = zgrid.read(data, "t.zg")
    assert back.colour_scale == grid.colour_scale and back.colors.tobytes() == grid.colors.tobytes()
    if scaled:
        assert back.fine_colors.tobytes() == grid.fine_colors.tobytes()
        assert not back.fine_colors[~fine_mask(back.valid, scale)].any()
        assert back.colors.tobytes() == back.fine_colors[::scale, ::scale].tobytes()
    else:   # scale 1 is today's 5.0 file, byte for byte
        assert data == zgrid.write(ZGrid(grid.z, 0.5, 0.25, units="mm", colors=grid.colors), raw="float64")
    assert zgrid.write(back, raw="float64") == data


@settings(max_examples=100, deadline=None, derandomize=True)
@given(fine_grids().filter(lambda case: case[0].colour_scale > 1), st.data())
def test_a_damaged_6_0_zgrid_is_refused_in_one_line(case, data):
    """Cut short, added to, without its colour_scale line or with a scale that does not fit: an
    MzcError naming the field (the crc32 fixed up, so the reader's own checks refuse it)."""
    grid, _scale = case
    good = zgrid.write(grid, raw="float64")
    cut = data.draw(st.integers(1, 3 * grid.fine_colors[..., 0].size))
    line = f"colour_scale {grid.colour_scale}\n".encode()
    for bad in (good[:-cut], good + b"\0" * cut, good.replace(line, b""), good.replace(line, b"colour_scale 9\n"),
                good.replace(line, b"colour_scale 1\n"), good.replace(line, b"colour_scale two\n")):
        with pytest.raises(MzcError) as error:
            zgrid.read(rechecksummed(bad), "bad.zg")
        assert error.value.field in ("data", "colour_scale") and "\n" not in str(error.value)


@st.composite
def fine_images(draw):
    """(fine image, node mask, scale): smooth ramps or noise on small node masks, scale 2..4."""
    shape = draw(st.tuples(st.integers(1, 9), st.integers(1, 9)))
    scale = draw(st.integers(2, 4))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    fine = ((shape[0] - 1) * scale + 1, (shape[1] - 1) * scale + 1)
    if draw(st.booleans()):
        r, c = np.mgrid[0:fine[0], 0:fine[1]]
        rgb = np.stack([r * 255 // max(fine[0] - 1, 1), c * 255 // max(fine[1] - 1, 1), (r * c) % 256], axis=-1)
    else:
        rgb = rng.integers(0, 256, (*fine, 3))
    mask = rng.random(shape) < draw(st.sampled_from([0.0, 0.6, 1.0]))
    return rgb.astype(np.uint8), mask, scale


@settings(max_examples=60, deadline=None)
@given(fine_images(), st.sampled_from([0, 2, 5]))
def test_the_colour_section_codes_fine_colours_within_the_bound(image, max_error):
    rgb, mask, scale = image
    section = colour.encode_colour(rgb, mask, max_error=max_error, scale=scale)
    assert section[4] == colour.FINE_VERSION and section[13] == scale
    decoded = colour.decode_colour(section, mask)
    samples = fine_mask(mask, scale)
    assert decoded.shape == rgb.shape and not decoded[~samples].any()
    assert np.abs(decoded.astype(int) - rgb)[samples].max(initial=0) <= max_error
    assert colour.section_length(section + b"more") == len(section)


@settings(max_examples=40, deadline=None)
@given(fine_grids().filter(lambda case: case[0].valid.any()), st.sampled_from([0, 3]))
def test_fine_colours_round_trip_through_a_dwt2d_file(case, max_error):
    """A whole dwt2d file (8.0) of a grid with fine colours: the decoded grid has the same colour
    scale, every valid sample within the colour bound, the nodes' colours its node samples."""
    import mzc

    grid, _scale = case
    back = mzc.decode(mzc.encode(grid, "dwt2d", max_error=1.0, colour_max_error=max_error))
    assert back.colour_scale == grid.colour_scale
    image, want = ((back.colors, grid.colors) if grid.fine_colors is None else (back.fine_colors, grid.fine_colors))
    samples = fine_mask(back.valid, back.colour_scale)
    assert np.array_equal(back.valid, grid.valid) and not image[~samples].any()
    assert np.abs(image.astype(int) - want)[samples].max(initial=0) <= max_error


def test_scale_1_writes_version_1_byte_for_byte():
    rng = np.random.default_rng(3)
    rgb, mask = rng.integers(0, 256, (12, 10, 3)).astype(np.uint8), rng.random((12, 10)) < 0.8
    assert colour.encode_colour(rgb, mask, max_error=3, scale=1) == colour.encode_colour(rgb, mask, max_error=3)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(st.data())
def test_a_damaged_version_2_section_or_another_mask_is_refused(data):
    rng = np.random.default_rng(7)
    mask = rng.random((6, 7)) < 0.8
    rgb = rng.integers(0, 256, (11, 13, 3)).astype(np.uint8)
    section = colour.encode_colour(rgb, mask, max_error=2, scale=2)
    damaged = bytearray(section)
    damaged[data.draw(st.integers(0, len(section) - 1))] ^= data.draw(st.integers(1, 255))
    for bad, bad_mask in ((bytes(damaged), mask), (section, mask[:, 1:]), (section[:-1], mask)):
        with pytest.raises(MzcError) as error:
            colour.decode_colour(bad, bad_mask, source="a.mzw2")
        assert str(error.value).startswith("a.mzw2: colour: ") and "\n" not in str(error.value)


def spec_example_2():
    """(the version 2 worked example's bytes, its node mask, its image) from spec/colour.md."""
    from pathlib import Path

    blocks = (Path(__file__).resolve().parents[1] / "spec" / "colour.md").read_text().split("```")
    block = lambda name: next(b for b in blocks if b.startswith(name + "\n")).split("\n", 1)[1]  # noqa: E731
    section = bytes.fromhex("".join(block("hex-2").split()))
    samples = np.array([[c == "#" for c in row] for row in block("mask-2").split()])
    rgb = np.array([[int(v) for v in row.split()] for row in block("rgb-2").strip().splitlines()])
    return section, samples, rgb.reshape(*samples.shape, 3)


def test_the_spec_version_2_example_decodes_to_the_image_it_shows():
    section, samples, rgb = spec_example_2()
    nodes = samples[::2, ::2]
    assert fine_mask(nodes, 2).tolist() == samples.tolist()
    assert np.array_equal(colour.decode_colour(section, nodes), rgb)
    assert colour.encode_colour(rgb.astype(np.uint8), nodes, max_error=0, scale=2) == section   # as mzc wrote it


def spec_example_3():
    """(the version 3 worked example's bytes, its node mask, its charts, its image) from spec/colour.md."""
    from pathlib import Path

    from mzc.grid import Chart

    text = (Path(__file__).resolve().parents[1] / "spec" / "colour.md").read_text()
    blocks = text.split("```")
    block = lambda name: next(b for b in blocks if b.startswith(name + "\n")).split("\n", 1)[1]  # noqa: E731
    section = bytes.fromhex("".join(block("hex-3").split()))
    samples = np.array([[c == "#" for c in row] for row in block("mask-3").split()])
    rgb = np.array([[int(v) for v in row.split()] for row in block("rgb-3").strip().splitlines()])
    words = text.split("The charts (view, row0, col0, rows, cols, i0, j0; the decoder is given them) are\n")[1]
    charts = tuple(Chart(view, *map(int, numbers)) for view, *numbers in
                   (chart.split() for chart in words.split("`")[1:4:2]))
    return section, samples[::2, ::2], charts, rgb.reshape(*samples.shape, 3)


def test_the_spec_version_3_example_decodes_to_the_image_it_shows():
    section, nodes, charts, rgb = spec_example_3()
    assert nodes.all() and [chart.col0 for chart in charts] == [0, 2]
    samples = (rgb != 0).any(axis=-1)
    assert fine_mask(nodes, 2, charts).tolist() == samples.tolist() and not samples[:, 3].any()
    assert np.array_equal(colour.decode_colour(section, nodes, charts=charts), rgb)
    assert colour.encode_colour(rgb.astype(np.uint8), nodes, max_error=0, scale=2, levels=1, charts=charts) == section
    with pytest.raises(MzcError, match="version 3 belongs to a multi-chart grid"):
        colour.decode_colour(section, nodes, source="a.mzw2")
    as_version_2 = bytearray(section)   # what a decoder that ignored the charts would read
    as_version_2[4] = colour.FINE_VERSION
    as_version_2[27:31] = zlib.crc32(as_version_2[31:], zlib.crc32(as_version_2[:27])).to_bytes(4, "little")
    assert colour.decode_colour(bytes(as_version_2), nodes)[0, 3].tolist() == [103, 63, 123]   # the spec's words


def two_charts():
    """Two charts side by side on a 2 x 4 grid: columns 0-1 looking along +z, 2-3 along -x."""
    from mzc.grid import Chart

    return Chart("+z", 0, 0, 2, 2, 0, 0), Chart("-x", 0, 2, 2, 2, 5, 0)


def test_a_multi_chart_grid_holds_each_charts_finer_block_and_nothing_between():
    """The samples between two charts' blocks are invalid (0 once in the grid), each chart grid
    gets its block of the image, and the grid round-trips through the z-grid 6.0 and a dwt2d file."""
    import mzc

    fine = np.arange(3 * 7 * 3).reshape(3, 7, 3) % 200 + 50
    grid = ZGrid(np.ones((2, 4)), 1, 1, charts=two_charts(), fine_colors=fine)
    assert grid.colour_scale == 2 and not grid.fine_colors[:, 3].any()
    assert grid.fine_colors[:, [0, 1, 2, 4, 5, 6]].tolist() == fine[:, [0, 1, 2, 4, 5, 6]].tolist()
    left, right = grid.chart_grids()
    assert left.fine_colors.tolist() == fine[:, :3].tolist() and right.fine_colors.tolist() == fine[:, 4:].tolist()
    data = zgrid.write(grid, raw="float64")
    assert data.startswith(b"mzc-zgrid 6.0\n") and zgrid.write(zgrid.read(data, "g.zg"), raw="float64") == data
    coded = mzc.encode(grid, "dwt2d", max_error=0.01, colour_max_error=0)
    back = mzc.decode(coded)
    assert back.charts == grid.charts and back.fine_colors.tobytes() == grid.fine_colors.tobytes()


@settings(max_examples=40, deadline=None)
@given(fine_grids().filter(lambda case: case[0].colour_scale > 1 and case[0].valid.any()), st.data())
def test_multi_chart_grids_fine_colours_round_trip_through_the_zgrid_and_a_dwt2d_file(case, data):
    """Any grid split into charts side by side, with colours 2..4 times finer (any bytes, those
    between the charts too): the grid keeps the samples of its charts' cells alone, the z-grid 6.0
    gives them back byte for byte, and a dwt2d file losslessly (colour section version 3)."""
    import mzc

    plain, scale = case
    charts = data.draw(side_by_side_charts(plain.shape))
    grid = ZGrid(plain.z, 0.5, 0.25, units="mm", charts=charts, fine_colors=plain.fine_colors)
    samples = fine_mask(grid.valid, scale, charts)
    assert grid.fine_colors[samples].tobytes() == plain.fine_colors[samples].tobytes()
    assert not grid.fine_colors[~samples].any()
    text = zgrid.write(grid, raw="float64")
    assert zgrid.write(zgrid.read(text, "g.zg"), raw="float64") == text
    back = mzc.decode(mzc.encode(grid, "dwt2d", max_error=1.0, colour_max_error=0))
    assert back.charts == charts and back.fine_colors.tobytes() == grid.fine_colors.tobytes()


@settings(max_examples=60, deadline=None)
@given(fine_images(), st.sampled_from([0, 3]), st.data())
def test_a_version_3_section_codes_a_multi_chart_grids_samples_within_the_bound(image, max_error, data):
    rgb, mask, scale = image
    charts = data.draw(side_by_side_charts(mask.shape))
    section = colour.encode_colour(rgb, mask, max_error=max_error, scale=scale, charts=charts)
    assert section[4] == colour.CHARTED_VERSION and section[13] == scale
    decoded = colour.decode_colour(section, mask, charts=charts)
    samples = fine_mask(mask, scale, charts)
    assert not decoded[~samples].any()
    assert np.abs(decoded.astype(int) - rgb)[samples].max(initial=0) <= max_error
    with pytest.raises(MzcError, match="version 3 belongs to a multi-chart grid"):
        colour.decode_colour(section, mask)
    fine = colour.encode_colour(rgb, mask, max_error=max_error, scale=scale)
    with pytest.raises(MzcError, match="version 2 belongs to a grid without charts"):
        colour.decode_colour(fine, mask, charts=charts)


def test_new_values_of_another_shape_or_new_colours_leave_the_fine_colours_behind():
    grid = ZGrid(np.ones((3, 3)), 1, 1, fine_colors=np.full((5, 5, 3), 7))
    assert grid.with_z(grid.z, units="mm").colour_scale == 2
    assert grid.with_z(grid.z[:2]).fine_colors is None and grid.with_z(grid.z[:2]).colors is None
    recoloured = grid.with_z(grid.z, colors=np.zeros((3, 3, 3)))
    assert recoloured.colour_scale == 1 and not recoloured.colors.any()


def test_a_window_keeps_the_samples_of_its_cells():
    from mzc.codecs.dwt2d.tiles import window_of

    grid = ZGrid(np.arange(20.0).reshape(4, 5), 1, 1, fine_colors=np.arange(7 * 9 * 3).reshape(7, 9, 3) % 256)
    window = window_of(grid, (1, 2, 2, 3))
    assert window.colour_scale == 2 and window.fine_colors.tolist() == grid.fine_colors[2:5, 4:9].tolist()
    assert window.colors.tolist() == grid.colors[1:3, 2:5].tolist()


def test_densify_keeps_the_nodes_colours_and_names_the_finer_ones_it_drops():
    import warnings

    from mzc.errors import MzcWarning
    from mzc.ops.densify import densify_grid

    grid = ZGrid(np.add.outer(np.arange(4.0), np.arange(5.0)), 1, 1, fine_colors=np.full((7, 9, 3), 90))
    assert densify_grid(grid, 0).colour_scale == 2
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dense = densify_grid(grid, 1)
    assert dense.fine_colors is None and dense.colors.shape == (7, 5, 3) and (dense.colors == 90).all()
    assert [str(w.message) for w in caught if issubclass(w.category, MzcWarning)] == [
        "not kept: the colours 2 times finer than the nodes (densify keeps the nodes' colours, mixed for the rows "
        "it inserts)"]


# --------------------------------------------------------------------------- slicing


def test_slice_samples_between_the_nodes_on_the_surface():
    """On the generated height field (colour a smooth function of x and y), every valid sample of
    a grid sampled 4 times finer is the colour at its own point, within the mesh's interpolation
    error; the node samples are the nodes' colours at scale 1, exactly."""
    from test_colour import analytic_colour, coloured_surface

    from mzc.ops.slicing import slice_surface

    mesh = coloured_surface()
    plain, fine = slice_surface(mesh, d1=0.4), slice_surface(mesh, d1=0.4, colour_scale=4)
    assert fine.colour_scale == 4 and fine.colors.tobytes() == plain.colors.tobytes()
    samples = fine_mask(fine.valid, 4)
    v, u = np.mgrid[0:samples.shape[0], 0:samples.shape[1]] / 4.0
    x, y = fine.origin[0] + u * fine.d2, fine.origin[1] + v * fine.d1
    points = fine.to_input_frame(np.stack([x, y, np.zeros_like(x)], axis=-1))[samples]
    error = fine.fine_colors[samples].astype(float) - analytic_colour(points[:, 0], points[:, 1])
    assert np.abs(error).max() <= 3.0
    assert samples.sum() > 3 * fine.valid.sum()


def test_slice_samples_each_chart_of_a_multi_chart_grid_on_its_surface():
    """On the ball whose colour is linear in the position, a 6-chart grid sampled twice as finely:
    its node samples are the nodes' colours at scale 1, every valid sample is the colour at its
    point within 3 levels (each chart's samples at the points its own node lines place them), and
    no sample between two charts' blocks is valid."""
    from test_colour import ball

    from mzc.grid import fine_lattice
    from mzc.ops.slicing import slice_surface

    mesh, colour_of = ball()
    plain, fine = slice_surface(mesh, charts=6), slice_surface(mesh, charts=6, colour_scale=2)
    assert len(fine.charts) > 1 and fine.colors.tobytes() == plain.colors.tobytes()
    errors = []
    for part in fine.chart_grids():
        (low, high, _), (left, right, _) = (fine_lattice(n, 2) for n in part.shape)
        # at K = 2 the bilinear mix of a sample's cell is the mean of its (one, two or four) nodes
        z = (part.z[low][:, left] + part.z[high][:, right] + part.z[low][:, right] + part.z[high][:, left]) / 4
        v, u = np.mgrid[0:z.shape[0], 0:z.shape[1]] / 2.0
        points = part.to_input_frame(np.stack([part.origin[0] + u * part.d2, part.origin[1] + v * part.d1, z], -1))
        samples = fine_mask(part.valid, 2)
        errors.append(np.abs(part.fine_colors[samples] - colour_of(points[samples])).max())
    assert max(errors) <= 3.0, errors
    between = np.ones(fine.fine_colors.shape[:2], dtype=bool)
    for chart in fine.charts:
        between[chart.block(2)] = False
    assert between.any() and not fine_mask(fine.valid, 2, fine.charts)[between].any()
    assert not fine.fine_colors[between].any()


def test_slice_refuses_a_colour_scale_it_cannot_honour_in_one_line(tmp_path):
    from test_colour import ball, coloured_surface

    from mzc.meshes import mesh_to_bytes

    (tmp_path / "ball.ply").write_bytes(mesh_to_bytes(ball()[0], "ply"))
    plain = coloured_surface()
    plain.colors = None
    (tmp_path / "plain.ply").write_bytes(mesh_to_bytes(plain, "ply"))
    (tmp_path / "g.zg").write_bytes(zgrid.write(ZGrid(np.ones((3, 3)), 1, 1), raw="float64"))
    for arguments, code, words in (
            (["ball.ply", "--colour-scale", "0"], 2, b"--colour-scale"),
            (["ball.ply", "--colour-scale", "9"], 2, b"--colour-scale"),
            (["ball.ply", "--colour-scale", "2.5"], 2, b"--colour-scale"),
            (["plain.ply", "--colour-scale", "2"], 1, b"has none"),
            (["g.zg", "--colour-scale", "2"], 1, b"colour_scale")):
        result = run_mzc("slice", *arguments, "-o", "out.zg", cwd=tmp_path)
        assert result.returncode == code, (arguments, result.stderr)
        assert words in result.stderr and b"Traceback" not in result.stderr
        if code == 1:
            assert len(result.stderr.decode().strip().splitlines()) == 1
    assert not (tmp_path / "out.zg").exists()
    import mzc

    for bad in (1.5, True, "2", 0, 9):
        with pytest.raises(MzcError, match="colour_scale"):
            mzc.slice(tmp_path / "ball.ply", charts=1, colour_scale=bad)


# --------------------------------------------------------------------------- the pipeline on fran


def rebuilt_colour_error(source, rebuilt, points):
    """RMS (8-bit levels) of the textured ``rebuilt`` mesh's colour, its texture looked up at its
    surface point nearest each of ``points``, against ``source``'s colour at them."""
    from mzc.ops.colouring import surface_colours

    error = surface_colours(points, rebuilt) - surface_colours(points, source)
    return float(np.sqrt(np.mean(error ** 2)))


@pytest.mark.parametrize("charts", ["1", "auto"])
def test_the_cli_pipeline_on_fran_gives_a_finer_texture_closer_to_the_source(tmp_path, charts):
    """slice --colour-scale 2 | encode --dwt2d | decode | triangulate --texture on VTK's fran, one
    grid or its charts (18): the PNG has (rows - 1) 2 + 1 by (cols - 1) 2 + 1 pixels, and the colour
    through the texture at points spread over the source surface (its triangles' centres and
    vertices) is closer to fran's own than at scale 1 (measured 0.65 -> 0.55 levels RMS on one
    grid, 0.72 -> 0.66 on the charts), the colours coded losslessly both ways (the sampling
    measured, not the coding)."""
    from PIL import Image

    import mzc
    from mzc.meshes import read_mesh

    source = read_mesh(fran())
    points = np.concatenate([source.points, source.points[source.triangles].mean(axis=1)])
    errors, shapes = {}, {}
    for scale in (1, 2):
        grid, coded, obj = (tmp_path / f"k{scale}.{ext}" for ext in ("zg", "mzw2", "obj"))
        decoded, png = tmp_path / f"k{scale}d.zg", tmp_path / f"k{scale}.png"
        run_mzc("slice", fran(), "--charts", charts, "--colour-scale", scale, "-o", grid, check=True)
        run_mzc("encode", grid, "--dwt2d", "--colour-max-error", "0", "-o", coded, check=True)
        run_mzc("decode", coded, "-o", decoded, check=True)
        run_mzc("triangulate", decoded, "-o", obj, "--texture", png, check=True)
        back = mzc.read(decoded)
        assert back.colour_scale == scale and (back.charts is None) == (charts == "1")
        with Image.open(png) as image:
            shapes[scale] = image.size
        assert shapes[scale] == ((back.shape[1] - 1) * scale + 1, (back.shape[0] - 1) * scale + 1)
        rebuilt = read_mesh(obj)
        assert rebuilt.texture is not None
        errors[scale] = rebuilt_colour_error(source, rebuilt, points)
    assert shapes[2][0] > 1.9 * shapes[1][0] and shapes[2][1] > 1.9 * shapes[1][1]
    assert errors[2] < 0.95 * errors[1], errors


def test_triangulate_textures_a_multi_chart_grid_seams_included(tmp_path):
    """slice --charts 6 --colour-scale 2 | triangulate --texture on the ball whose colour is linear
    in the position: the colour through the texture at 20,000 points all over the ball is the
    function's within 1 level RMS and 4 at most (measured 0.41 and 2.8). The seams' triangles
    join nodes of two charts' blocks of the image, so each takes one texel: with a texture
    coordinate per corner they would interpolate across the image between the blocks (measured
    83.7 levels RMS, 218 at most)."""
    from test_colour import ball

    from mzc.meshes import mesh_to_bytes, read_mesh
    from mzc.ops.colouring import surface_colours

    mesh, colour_of = ball()
    (tmp_path / "ball.ply").write_bytes(mesh_to_bytes(mesh, "ply"))
    run_mzc("slice", "ball.ply", "--charts", "6", "--colour-scale", "2", "-o", "ball.zg", cwd=tmp_path, check=True)
    run_mzc("triangulate", "ball.zg", "-o", "ball.obj", "--texture", "ball.png", cwd=tmp_path, check=True)
    rebuilt = read_mesh(tmp_path / "ball.obj")
    assert rebuilt.texture is not None
    points = np.random.default_rng(0).normal(size=(20_000, 3))
    points = 20 * points / np.linalg.norm(points, axis=1)[:, None] + [1.0, 2.0, 3.0]
    error = surface_colours(points, rebuilt) - colour_of(points)
    assert np.sqrt(np.mean(error ** 2)) <= 1.0 and np.abs(error).max() <= 4.0


def test_info_shows_the_colour_scale_of_a_dwt2d_file_and_a_zgrid(tmp_path):
    from mzc.codecs.dwt2d import encode_grid

    grid = ZGrid(np.arange(20.0).reshape(4, 5), 1, 1, fine_colors=np.full((7, 9, 3), 90))
    (tmp_path / "g.mzw2").write_bytes(encode_grid(grid, max_error=0.01))
    (tmp_path / "g.zg").write_bytes(zgrid.write(grid, raw="float64"))
    plain = ZGrid(grid.z, 1, 1, colors=grid.colors)
    (tmp_path / "plain.zg").write_bytes(zgrid.write(plain, raw="float64"))
    (tmp_path / "plain.mzw2").write_bytes(encode_grid(plain, max_error=0.01))
    for name in ("g.mzw2", "g.zg"):
        result = run_mzc("info", tmp_path / name, check=True)
        assert result.stdout.count(b"colour scale 2 (7 x 9 samples, 2 a node spacing)") == 1, name
    for name in ("plain.mzw2", "plain.zg"):
        assert b"colour scale" not in run_mzc("info", tmp_path / name, check=True).stdout


def test_batch_encode_takes_the_colour_scale_and_writes_the_bytes_of_slice_then_encode(tmp_path):
    """``mzc batch encode --colour-scale 2`` on fran: the file is byte for byte what ``mzc slice
    --colour-scale 2 | mzc encode --dwt2d`` writes, and decodes to its fine colours (the batch
    takes every slice option, this one included)."""
    pytest.importorskip("distributed")
    import mzc

    options = ("--colour-psnr", "40", "--rmse", "0.05")
    piped = tmp_path / "piped.mzw2"
    grid = tmp_path / "fran.zg"
    run_mzc("slice", fran(), "--charts", "1", "--colour-scale", "2", "-o", grid, check=True)
    run_mzc("encode", grid, "--dwt2d", *options, "-o", piped, check=True)
    run_mzc("batch", "encode", fran(), "-o", tmp_path / "out", "--charts", "1", "--colour-scale", "2",
            "--dwt2d", *options, "--workers", "1", check=True)
    batched = (tmp_path / "out" / "fran.mzw2").read_bytes()
    assert batched == piped.read_bytes()
    decoded = mzc.decode(batched)
    assert decoded.colour_scale == 2 and decoded.fine_colors.shape[:2] == (
        (decoded.shape[0] - 1) * 2 + 1, (decoded.shape[1] - 1) * 2 + 1)
