"""The browser mesh of web/ (issue 34, second part): `node web/cli.mjs triangulate IN` writes,
byte for byte, the OBJ `mzc triangulate IN --format obj` writes (the same vertices, bit for bit,
and the same triangles in the same order) for planar, cylindrical and spherical grids, full
turns, poles and depth jumps at several angles, geographic grids (placed in metres about
their centre as mzc places them), and multi-chart grids, their seams zipped by web/zipper.mjs
as mzc's zipper zips them (spec/zgrid.md, Zipping the charts): the fixtures, the sample blob,
a shared object, and web/zipper.mjs's zipCharts against mzc.ops.zipper.zip_charts on the
zipper tests' closed surfaces (the boxes' creases put back) and on triangle soups. Skipped when
node is not installed."""

import shutil
import subprocess

import numpy as np
import pytest
from test_zipper import bored_box, cube, hemisphere, sphere, torus, two_spheres

from mzc.formats import read_any, zgrid
from mzc.grid import Chart, ZGrid
from mzc.meshes.obj import write as obj_bytes
from mzc.ops.colouring import nearest_sources
from mzc.ops.triangulation import CHART_JUMP_ANGLE, GridMesh, grid_to_mesh
from mzc.ops.zipper import zip_charts

from charts import chart_meshes
from codec_contract import FIXTURES, fixture_bytes, fixture_names
from conftest import REPO, run_mzc
from web_node import NODE, WEB, needs_node

TO_1E12 = ("dft", "dct")   # web/ decodes them within an ulp, so their points may differ in the last bits

pytestmark = needs_node


def node_triangulate(path, *options):
    """`node web/cli.mjs triangulate PATH OPTIONS` as a finished process."""
    return subprocess.run([NODE, str(WEB / "cli.mjs"), "triangulate", str(path), *map(str, options)],
                          capture_output=True)


def mesh_obj(grid, jump_angle=None):
    """The OBJ mzc writes of ``grid``'s mesh (its charts' zipped)."""
    return obj_bytes(grid_to_mesh(grid, jump_angle))


def assert_same_mesh(grid, tmp_path, *jump_angles):
    """web/'s OBJ of ``grid`` (written as a raw z-grid) is mzc's at each jump angle."""
    path = tmp_path / "grid.zg"
    path.write_bytes(zgrid.write(grid, raw="float64"))
    for angle in jump_angles or (None,):
        made = node_triangulate(path, *(() if angle is None else ("--jump-angle", angle)))
        assert made.returncode == 0, made.stderr.decode()
        assert made.stdout == mesh_obj(grid, angle), f"jump angle {angle}"


@pytest.mark.parametrize("name", [n for n in fixture_names() if n.split("-")[0] not in TO_1E12])
def test_fixtures_triangulate_as_mzc_triangulate_does(name, tmp_path):
    out = tmp_path / "mesh.obj"
    run_mzc("triangulate", FIXTURES / name, "--vertices", "all", "--format", "obj", "-o", out, check=True)
    made = node_triangulate(FIXTURES / name)
    assert made.returncode == 0, made.stderr.decode()
    assert made.stdout == out.read_bytes()


@pytest.mark.parametrize("name", [n for n in fixture_names() if n.split("-")[0] in TO_1E12])
def test_dct_and_dft_grids_as_mzc_decodes_them_triangulate_as_mzc_does(name, tmp_path):
    assert_same_mesh(read_any(fixture_bytes(name), name), tmp_path)


def heights(rng, shape, base, spread, holes):
    """Random values about ``base`` with ``holes`` of them NaN (invalid)."""
    z = base + rng.normal(0, spread, shape)
    z.ravel()[rng.choice(z.size, holes, replace=False)] = np.nan
    return z


def test_planar_grids_with_depth_jumps(tmp_path):
    rng = np.random.default_rng(34)
    z = heights(rng, (9, 12), 5, 0.3, 10)
    z[:, 7:] += 60   # a wall: a jump at 3 degrees, not at 0
    z[4, 2] -= 40
    transform = np.array([[0, -1, 0, 4.5], [1, 0, 0, -2], [0, 0, 1, 7.25]], dtype=float)
    assert_same_mesh(ZGrid(z, d1=0.7, d2=1.3, origin=(-3.1, 2.2), transform=transform), tmp_path, None, 0, 10, 89)


def test_cylindrical_full_turn_and_part_turn(tmp_path):
    rng = np.random.default_rng(35)
    radius = 20.0
    for cols, span in ((16, 2 * np.pi), (10, np.pi)):
        z = heights(rng, (7, cols), radius, 0.5, 6)
        z[3, 5] = 3 * radius   # a spike: jumps across its neighbours
        assert_same_mesh(ZGrid(z, d1=2.5, d2=span * radius / cols, origin=(0.3, -4), projection="cylindrical",
                               radius=radius), tmp_path, None, 0, 20)


def test_cylindrical_grid_of_one_column_around_the_turn(tmp_path):
    z = np.full((5, 1), 10.0)
    assert_same_mesh(ZGrid(z, d1=1, d2=2 * np.pi * 8, projection="cylindrical", radius=8.0), tmp_path)


def test_spherical_grids_with_poles_fans_and_holes(tmp_path):
    rng = np.random.default_rng(36)
    radius = 50.0
    for rows, cols in ((7, 10), (13, 300)):   # 300 columns: a pole's mean summed over many points
        d1 = np.pi * radius / (rows - 1)
        z = heights(rng, (rows, cols), radius, 1.0, rows)
        z[0, :3] = np.nan   # a pole row's first nodes invalid: its vertex is the first valid one
        grid = ZGrid(z, d1=d1, d2=2 * np.pi * radius / cols, origin=(0.1, -np.pi * radius / 2),
                     projection="spherical", radius=radius,
                     transform=np.array([[0, 0, 1, 1], [0, 1, 0, -2], [-1, 0, 0, 3]], dtype=float))
        assert grid.pole_rows()[[0, -1]].all()
        assert_same_mesh(grid, tmp_path, None, 0, 30)


def test_charts_zip_as_mzc_zips_them(tmp_path):
    rng = np.random.default_rng(37)
    z = np.full((10, 14), np.nan)
    z[0:6, 0:5] = heights(rng, (6, 5), 3, 0.2, 2)
    z[1:10, 6:14] = heights(rng, (9, 8), -2, 0.2, 3)
    z[5, 9] = 40   # a step within a chart: a jump at 30 degrees
    charts = [Chart("+z", 0, 0, 6, 5, -3, 2), Chart("-x", 1, 6, 9, 8, 4, -1)]
    transform = np.array([[0, -1, 0, 4.5], [1, 0, 0, -2], [0, 0, 1, 7.25]], dtype=float)
    assert_same_mesh(ZGrid(z, d1=0.5, d2=0.5, transform=transform, charts=charts), tmp_path, None, 0, 5)


def coloured(grid, rng):
    """``grid`` with a random colour at every node (0 0 0 at its invalid ones, as mzc keeps them)."""
    return grid.with_z(grid.z, colors=rng.integers(0, 256, (*grid.z.shape, 3), dtype=np.uint8))


def test_coloured_grids_give_their_vertices_their_nodes_colours(tmp_path):
    """A coloured grid (mzc-zgrid 5.0) gives each vertex its node's colour, a pole's vertex its first
    valid node's, the zipper's added points their nearest chart point's, as mzc's OBJ has them."""
    rng = np.random.default_rng(38)
    radius = 20.0
    z = heights(rng, (9, 12), radius, 0.5, 9)
    z[0, :2] = np.nan
    sphere_grid = ZGrid(z, d1=np.pi * radius / 8, d2=2 * np.pi * radius / 12, origin=(0, -np.pi * radius / 2),
                        projection="spherical", radius=radius)
    assert_same_mesh(coloured(sphere_grid, rng), tmp_path, None, 0)
    run_mzc("sample", "blob", "-o", tmp_path / "blob.obj", check=True)
    run_mzc("slice", tmp_path / "blob.obj", "--charts", "6", "-o", tmp_path / "blob.zg", check=True)
    blob = read_any((tmp_path / "blob.zg").read_bytes(), "blob.zg")
    assert_same_mesh(coloured(blob, rng), tmp_path)


def chart_triangle_count(grid):
    """How many triangles ``grid``'s charts' meshes have before the zipper."""
    return sum(len(GridMesh(chart, CHART_JUMP_ANGLE).mesh().triangles) for chart in grid.chart_grids())


def assert_zipped_as_mzc(path, tmp_path):
    """web/'s OBJ of the multi-chart file ``path`` is `mzc triangulate --vertices all`'s, stitches and all."""
    run_mzc("triangulate", path, "--vertices", "all", "--format", "obj", "-o", tmp_path / "zipped.obj", check=True)
    made = node_triangulate(path)
    assert made.returncode == 0, made.stderr.decode()
    assert made.stdout == (tmp_path / "zipped.obj").read_bytes()
    grid = read_any(path.read_bytes(), path.name)
    assert made.stdout.count(b"\nf ") > chart_triangle_count(grid)   # the zipper's stitches


def test_the_blob_in_six_charts_zips_as_mzc_zips_it(tmp_path):
    run_mzc("sample", "blob", "-o", tmp_path / "blob.obj", check=True)
    run_mzc("slice", tmp_path / "blob.obj", "--charts", "6", "-o", tmp_path / "blob.zg", check=True)
    run_mzc("encode", "--dwt2d", "--rmse", "0.05", tmp_path / "blob.zg", "-o", tmp_path / "blob.mzw2", check=True)
    assert_zipped_as_mzc(tmp_path / "blob.mzw2", tmp_path)


def test_a_shared_object_in_charts_zips_as_mzc_zips_it(tmp_path):
    import mzc

    path = REPO.parent / "shared" / "data" / "objects" / "hand.ply"
    if not path.is_file():
        pytest.skip(f"shared object data not available ({path})")
    grid = mzc.slice(str(path))
    assert grid.charts is not None and len(grid.charts) > 1
    (tmp_path / "hand.zg").write_bytes(zgrid.write(grid, raw="float64"))
    run_mzc("encode", "--dwt2d", "--rmse", "0.05", tmp_path / "hand.zg", "-o", tmp_path / "hand.mzw2", check=True)
    assert_zipped_as_mzc(tmp_path / "hand.mzw2", tmp_path)


ZIP_SCRIPT = """
import { readFileSync } from "node:fs";
import { zipCharts } from "./zipper.mjs";
const cases = JSON.parse(readFileSync(process.argv[1], "utf8"));
process.stdout.write(JSON.stringify(cases.map(({ points, triangles, chart, spacing }) => {
  const { positions, indices } = zipCharts(Float64Array.from(points), Uint32Array.from(triangles), chart, spacing);
  return { points: Array.from(positions), triangles: Array.from(indices) };
})));
"""


SURFACE_SHAPES = (sphere, cube, torus, two_spheres, bored_box, hemisphere)
SURFACES = {shape.__name__ for shape in SURFACE_SHAPES}


def zip_cases():
    """(name, points, triangles, chart, spacing) of chart meshes to zip: the zipper tests' closed
    and open surfaces in charts at D/150 (welds on lattice edges, flat faces whose equally far
    neighbours tie, junctions of three charts), and seeded triangle soups on random charts
    (repeated, degenerate and inconsistently wound triangles, coincident points)."""
    for shape in SURFACE_SHAPES:
        points, triangles = shape()
        points = np.asarray(points, dtype=float)
        spacing = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) / 150
        yield (shape.__name__, *chart_meshes(points, triangles, spacing), spacing)
    for seed in range(150):
        rng = np.random.default_rng(seed)
        count = int(rng.integers(3, 31))
        points = rng.normal(size=(count, 3))
        points = np.round(points, 1) if rng.random() < 0.5 else points
        triangles = rng.integers(0, count, (int(rng.integers(0, 41)), 3))
        yield (f"soup {seed}", points, triangles, rng.integers(0, int(rng.integers(1, 5)), count),
               float(rng.choice([1e-3, 0.1, 1.0, 10.0])))


def test_zip_charts_gives_mzc_zippers_points_and_triangles(tmp_path):
    import json

    cases = list(zip_cases())
    (tmp_path / "cases.json").write_text(json.dumps([
        {"points": points.ravel().tolist(), "triangles": np.ravel(triangles).tolist(),
         "chart": np.ravel(chart).tolist(), "spacing": spacing} for _name, points, triangles, chart, spacing in cases]))
    run = subprocess.run([NODE, "--input-type=module", "-e", ZIP_SCRIPT, str(tmp_path / "cases.json")],
                         capture_output=True, cwd=WEB, timeout=300)
    assert run.returncode == 0, run.stderr.decode()
    stitched, pointed = [], []
    for (name, points, triangles, chart, spacing), made in zip(cases, json.loads(run.stdout), strict=True):
        zipped_points, zipped_triangles = zip_charts(points, triangles, chart, spacing)
        assert np.array_equal(np.reshape(made["points"], (-1, 3)), zipped_points), name
        assert np.array_equal(np.reshape(made["triangles"], (-1, 3)), zipped_triangles), name
        stitched += [name] if len(zipped_triangles) > len(triangles) else []
        pointed += [name] if len(zipped_points) > len(points) else []
    assert not SURFACES.difference(stitched)   # not meshes the zipper leaves alone
    assert len(stitched) > len(SURFACES) + 20   # nor soups
    assert {"cube", "bored_box"} <= set(pointed)   # the creases of the boxes' edges put back (step 10)


NEAREST_SCRIPT = """
import { readFileSync } from "node:fs";
import { nearestColours } from "./zipper.mjs";
const cases = JSON.parse(readFileSync(process.argv[1], "utf8"));
process.stdout.write(JSON.stringify(cases.map(({ points, count, colors }) =>
  Array.from(nearestColours(Float64Array.from(points), count, Uint8Array.from(colors))))));
"""


def test_points_the_zipper_adds_take_their_nearest_points_colour(tmp_path):
    """nearestColours colours the points mzc's zipper adds (zip_charts on the zipper cases) as
    mzc.ops.triangulation.every_node does (nearest_sources): the colour of the nearest of the charts' points, where
    one is nearest; of equally near ones (an added point midway on a cube's edge) the spec names
    none (mzc takes its search tree's), web/ the first: both then give one of theirs."""
    import json

    cases = []
    for name, points, triangles, chart, spacing in zip_cases():
        zipped = zip_charts(points, triangles, chart, spacing)[0]
        if len(zipped) > len(points):
            colours = np.random.default_rng(len(cases)).integers(0, 256, (len(points), 3), dtype=np.uint8)
            cases.append((name, zipped, len(points), colours))
    assert len(cases) > 5
    (tmp_path / "cases.json").write_text(json.dumps([
        {"points": zipped.ravel().tolist(), "count": count, "colors": colours.ravel().tolist()}
        for _name, zipped, count, colours in cases]))
    run = subprocess.run([NODE, "--input-type=module", "-e", NEAREST_SCRIPT, str(tmp_path / "cases.json")],
                         capture_output=True, cwd=WEB, timeout=300)
    assert run.returncode == 0, run.stderr.decode()
    ties = 0
    for (name, zipped, count, colours), made in zip(cases, json.loads(run.stdout), strict=True):
        made = np.reshape(made, (-1, 3))
        assert np.array_equal(made[:count], colours), name
        mzc_colours = colours[nearest_sources(zipped[count:], zipped[:count])]
        for point, got, want in zip(zipped[count:], made[count:], mzc_colours):
            distances = ((zipped[:count] - point) ** 2).sum(axis=1)
            nearest = colours[distances == distances.min()].tolist()
            assert got.tolist() in nearest and want.tolist() in nearest, name
            ties += len(nearest) > 1
    assert ties < sum(len(zipped) - count for _name, zipped, count, _colours in cases)   # not all ties


@pytest.fixture(scope="module")
def with_three(tmp_path_factory):
    """A folder holding a copy of web/ as web/ and three.js from npm in node_modules (nothing of
    it committed); skips when npm is missing or cannot install three."""
    folder = tmp_path_factory.mktemp("three")
    npm = shutil.which("npm")
    if npm is None:
        pytest.skip("npm is not installed")
    installed = subprocess.run([npm, "install", "--prefix", str(folder), "--no-audit", "--no-fund", "three"],
                               capture_output=True, timeout=120)
    if installed.returncode != 0:
        pytest.skip(f"npm could not install three: {installed.stderr.decode()[-200:]}")
    shutil.copytree(WEB, folder / "web", ignore=shutil.ignore_patterns("node_modules"))
    return folder


LOADER_SCRIPT = """
import { readFileSync } from "node:fs";
import { MZCLoader } from "./web/MZCLoader.mjs";
const [path, url] = process.argv.slice(2);
globalThis.ProgressEvent ??= class extends Event {   // a browser's, which three's FileLoader makes
  constructor(type, init) { super(type); Object.assign(this, init); }
};
const parsed = new MZCLoader().parse(readFileSync(path));
const loaded = await new MZCLoader().loadAsync(url);
const array = (attribute) => Array.from(attribute.array);
const color = parsed.attributes.color;
process.stdout.write(JSON.stringify({ info: parsed.userData.mzc, position: array(parsed.attributes.position),
  normal: parsed.attributes.normal.count, index: array(parsed.index), loaded: array(loaded.index),
  color: color && { values: array(color), normalized: color.normalized, type: color.array.constructor.name } }));
"""


def serving(folder):
    """Python's http.server serving ``folder`` on a free port of 127.0.0.1, in a thread: (server, URL
    of the folder); server.shutdown() stops it."""
    import functools
    import http.server
    import threading

    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):
            """Logs nothing (the test's output is its own)."""

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Quiet, directory=str(folder)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server, f"http://127.0.0.1:{server.server_address[1]}"


@pytest.fixture(scope="module")
def served():
    """The fixtures served over HTTP: served(name) -> URL."""
    server, url = serving(FIXTURES)
    yield lambda name: f"{url}/{name}"
    server.shutdown()


@pytest.mark.parametrize("name", ["dwt2d-3.0.mzw2", "zgrid-2.0.zg", "dwt2d-4.0.mzw2", "dwt2d-7.0.mzw2", "zgrid-5.0.zg"])
def test_three_loader_gives_mzc_mesh_as_a_buffer_geometry(with_three, served, name):
    import json

    script = with_three / "loader.mjs"
    script.write_text(LOADER_SCRIPT)
    run = subprocess.run([NODE, str(script), str(FIXTURES / name), served(name)], capture_output=True, cwd=with_three,
                         timeout=60)
    assert run.returncode == 0, run.stderr.decode()
    made = json.loads(run.stdout)
    grid = read_any(fixture_bytes(name), name)
    mesh = grid_to_mesh(grid)
    info = made["info"]
    assert (info["bytes"], info["rows"], info["cols"]) == (len(fixture_bytes(name)), *grid.z.shape)
    assert info["nodes"] == np.count_nonzero(np.isfinite(grid.z))
    assert (info["vertices"], info["triangles"]) == (len(mesh.points), len(mesh.triangles))
    assert made["normal"] == len(mesh.points)
    centre = (mesh.points.min(axis=0) + mesh.points.max(axis=0)) / 2
    assert info["centre"] == centre.tolist()
    assert np.array_equal(np.float32(made["position"]), (mesh.points - centre).astype(np.float32).ravel())
    assert made["index"] == made["loaded"] == mesh.triangles.ravel().tolist()
    if mesh.colors is None:
        assert "color" not in made
    else:   # a coloured grid's vertex colours, uint8 read as 0..1
        assert made["color"] == {"values": mesh.colors.ravel().tolist(), "normalized": True, "type": "Uint8Array"}


RECENTRED_SCRIPT = """
import { readFileSync } from "node:fs";
import { decode } from "./mzc.mjs";
import { recentred, triangulate } from "./triangulate.mjs";
const { local, centre } = recentred(triangulate(decode(readFileSync(process.argv[1]))).positions);
process.stdout.write(JSON.stringify({ local: Array.from(local), centre }));
"""


def test_positions_about_their_centre_keep_a_far_off_grids_detail(tmp_path):
    import json

    rng = np.random.default_rng(39)
    z = 1500 + np.cumsum(rng.normal(0, 0.01, (40, 50)), axis=1)   # centimetre relief
    transform = np.array([[0, -1, 0, 4_000_100.123], [1, 0, 0, 500_000.456], [0, 0, 1, 0.0]])   # UTM-like metres
    grid = ZGrid(z, d1=0.37, d2=0.41, origin=(250.3, -12.7), transform=transform)
    path = write_grid(grid, tmp_path)[0]
    run = subprocess.run([NODE, "--input-type=module", "-e", RECENTRED_SCRIPT, str(path)], capture_output=True,
                         cwd=WEB, timeout=60)
    assert run.returncode == 0, run.stderr.decode()
    made = json.loads(run.stdout)
    points = grid_to_mesh(grid).points
    centre = (points.min(axis=0) + points.max(axis=0)) / 2
    assert made["centre"] == centre.tolist()
    local = np.float32(made["local"]).reshape(-1, 3)
    assert np.array_equal(local, (points - centre).astype(np.float32))
    extent = np.ptp(points, axis=0).max()
    assert np.abs(local + centre - points).max() <= extent * 2.0 ** -24   # float32's rounding of the extent
    assert np.abs(points.astype(np.float32) - points).max() > 0.05   # as the input frame's float32: decimetres


CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CDN = "https://cdn.jsdelivr.net/npm/three@0.187.0/"   # viewer.html's import map: served from npm's copy here
BACKGROUND = (0x20, 0x24, 0x2A)   # viewer.mjs's scene background


def chromium(url, *options):
    """Headless Chromium's output (``--dump-dom``, or a ``--screenshot``) of ``url``, given five
    seconds of the page's (virtual) time, WebGL in SwiftShader (no GPU)."""
    run = subprocess.run([CHROMIUM, "--headless=new", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
                          "--use-angle=swiftshader", "--window-size=800,600", "--virtual-time-budget=5000",
                          *options, url], capture_output=True, timeout=60)
    assert run.returncode == 0, run.stderr.decode()[-500:]
    return run.stdout.decode()


@pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not installed (apt-get install chromium)")
def test_viewer_in_headless_chromium_shows_the_surface_and_its_nodes(with_three, tmp_path):
    import re

    PIL = pytest.importorskip("PIL.Image")
    name = "dwt2d-3.0.mzw2"
    site = with_three / "web"
    page = (WEB / "viewer.html").read_text()
    assert CDN in page
    (site / "viewer.html").write_text(page.replace(CDN, "../node_modules/three/"))
    shutil.copy(FIXTURES / name, site / name)
    run_mzc("triangulate", FIXTURES / name, "--format", "ply", "-o", site / "original.ply", check=True)
    server, url = serving(with_three)
    try:
        address = f"{url}/web/viewer.html?file={name}&original=original.ply"
        dom = chromium(address, "--dump-dom")
        chromium(address, f"--screenshot={tmp_path / 'shot.png'}")
    finally:
        server.shutdown()
    assert 'data-state="ready"' in dom, dom[-2000:]
    nodes = re.search(r'<tr id="nodes"><td>nodes</td><td>([0-9,]+)</td>', dom)
    grid = read_any(fixture_bytes(name), name)
    assert nodes and int(nodes[1].replace(",", "")) == np.count_nonzero(np.isfinite(grid.z))
    largest = re.search(r"<td>largest error</td><td>([0-9.e+-]+)( [^<]*)?</td>", dom)
    assert largest and float(largest[1]) < 1e-4   # its own mesh: float32 positions' rounding
    shot = np.asarray(PIL.open(tmp_path / "shot.png").convert("RGB"))[:, 330:]   # right of the panel
    surface = np.any(np.abs(shot.astype(int) - BACKGROUND) > 8, axis=-1)
    assert surface.mean() > 0.02, "the canvas is blank"
    assert len(np.unique(shot[surface].reshape(-1, 3) // 8, axis=0)) > 10, "the surface is not lit (one flat colour)"


def test_geographic_grids_in_metres_about_their_centre(tmp_path):
    rng = np.random.default_rng(38)
    wkt = ('GEOGCRS["a sphere",DATUM["d",ELLIPSOID["s",6371000,0]],CS[ellipsoidal,2],'
           'ANGLEUNIT["grad",0.015707963267948967]]')
    wgs84 = 'GEOGCS["WGS 84",DATUM["x",SPHEROID["WGS 84",6378137,298.257223563]],UNIT["degree",0.0174532925199433]]'
    for crs in (wkt, wgs84):
        z = heights(rng, (8, 11), 1200, 40, 5)
        z[2, 3] += 30000   # a cliff: a jump in metres, not in degrees
        assert_same_mesh(ZGrid(z, d1=1 / 1200, d2=1 / 1200, origin=(7.25, 46.5), crs=crs), tmp_path, None, 0)


ORIGINAL_SCRIPT = """
import { readFileSync } from "node:fs";
import { readMesh, Distance } from "./original.mjs";
const [path, lift] = [process.argv[1], Number(process.argv[2])];
const mesh = readMesh(readFileSync(path), path);
const distance = new Distance(mesh);
const lifted = Array.from({ length: mesh.points.length / 3 }, (_, i) =>
  distance.to(mesh.points[3 * i], mesh.points[3 * i + 1], mesh.points[3 * i + 2] + lift));
const [points, triangles] = [Array.from(mesh.points), Array.from(mesh.triangles)];
process.stdout.write(JSON.stringify({ points, triangles, lifted }));
"""


@pytest.mark.parametrize("file_format", ["ply", "obj"])
def test_viewer_reads_the_original_mesh_and_measures_distances_to_it(file_format, tmp_path):
    import json

    grid = ZGrid(np.add.outer(np.arange(7.0) * 0.1, np.arange(9.0) * 0.05), d1=1, d2=1)   # a tilted plane
    mesh = grid_to_mesh(grid)
    path = tmp_path / f"original.{file_format}"
    run_mzc("triangulate", *write_grid(grid, tmp_path), "--format", file_format, "-o", path, check=True)
    run = subprocess.run([NODE, "--input-type=module", "-e", ORIGINAL_SCRIPT, str(path), "0.5"], capture_output=True,
                         cwd=WEB, timeout=60)
    assert run.returncode == 0, run.stderr.decode()
    made = json.loads(run.stdout)
    assert np.array_equal(np.reshape(made["points"], (-1, 3)), mesh.points)
    assert np.array_equal(np.reshape(made["triangles"], (-1, 3)), mesh.triangles)
    normal = np.array([-0.05, -0.1, 1.0])
    inside = np.zeros((7, 9), dtype=bool)
    inside[1:-1, 1:-1] = True   # whose foot on the plane lies within the mesh
    assert np.allclose(np.array(made["lifted"])[inside.ravel()], 0.5 / np.linalg.norm(normal), rtol=1e-12, atol=0)


def write_grid(grid, folder):
    """``grid`` written as a raw z-grid in ``folder``: [its path]."""
    path = folder / "grid.zg"
    path.write_bytes(zgrid.write(grid, raw="float64"))
    return [path]


def test_negative_zeros_come_out_as_mzc_writes_them(tmp_path):
    z = np.array([[-0.0, 1, -0.0], [2, -0.0, 3], [-0.0, -0.0, -0.0]])   # an identity transform makes them 0
    assert_same_mesh(ZGrid(z, d1=1, d2=1, origin=(-0.0, -0.0)), tmp_path)


def random_grid(rng):
    """A small grid of a random projection, extent (full turns and poles often), holes, spread
    of values and transform."""
    projection = str(rng.choice(["planar", "cylindrical", "spherical"]))
    rows, cols = int(rng.integers(1, 9)), int(rng.integers(1, 12))
    z = rng.normal(0, rng.choice([0.01, 1, 30]), (rows, cols))
    z[rng.random((rows, cols)) < rng.uniform(0, 0.4)] = np.nan
    rotation = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    rotation[:, 0] *= np.sign(np.linalg.det(rotation))   # a rotation, not a reflection
    turned = {"transform": np.hstack([rotation, rng.normal(0, 50, (3, 1))])} if rng.random() < 0.5 else {}
    if projection == "planar":
        return ZGrid(z, d1=rng.uniform(0.1, 3), d2=rng.uniform(0.1, 3), origin=tuple(rng.normal(0, 10, 2)), **turned)
    radius = rng.uniform(1, 100)
    d2 = 2 * np.pi * radius / cols if rng.random() < 0.6 else rng.uniform(0.1, 2 * np.pi * radius / cols)
    d1, origin = rng.uniform(0.1, 3), tuple(rng.normal(0, 10, 2))
    if projection == "spherical":
        poles = rows > 1 and rng.random() < 0.6
        d1 = np.pi * radius / (rows - 1) if poles else rng.uniform(0.01, np.pi * radius / (rows + 1))
        span, room = (rows - 1) * d1, np.pi * radius / 2 - (rows - 1) * d1 / 2   # without poles: within them
        origin = (rng.normal(), -np.pi * radius / 2) if poles else (0.0, rng.uniform(-0.9, 0.9) * room - span / 2)
    return ZGrid(np.abs(radius + z), d1=d1, d2=d2, origin=origin, projection=projection, radius=radius, **turned)


@pytest.mark.parametrize("seed", range(40))
def test_random_grids(seed, tmp_path):
    rng = np.random.default_rng(seed)
    assert_same_mesh(random_grid(rng), tmp_path, rng.choice([None, 0, 1, 3, 20, 60]))
