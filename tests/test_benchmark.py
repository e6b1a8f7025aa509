"""The rate-distortion benchmark (benchmarks/rd.py): its metric on known cases, the grid peers'
container and codecs on a small central grid, the summary ratios, and a --quick run."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from mzc.grid import ZGrid
from mzc.measure.metrics import heightfield_filters, surface_distance, surface_distance_parts

from codec_contract import header_fields
from conftest import REPO, face_path, run_mzc

BENCHMARK = REPO / "benchmarks" / "rd.py"
sys.path.insert(0, str(BENCHMARK.parent))

import codec_limits  # noqa: E402
import contenders  # noqa: E402
import encoder_gains  # noqa: E402
import rd  # noqa: E402
import report  # noqa: E402


def flat_mesh(shift=0.0):
    """A 40 x 30 mm flat patch at z = shift (1 mm grid)."""
    return contenders.mesh_pair(ZGrid(np.full((31, 41), shift), 1.0, 1.0))


def wall_mesh():
    """A vertical 10 x 10 mm wall in the plane y = 0 (its normals are horizontal)."""
    points = np.array([[0, 0, 0], [10, 0, 0], [0, 0, 10], [10, 0, 10]], dtype=float)
    return points, np.array([[0, 1, 2], [1, 3, 2]])


def parts_of(mesh_a, mesh_b, samples=4000):
    return surface_distance_parts(mesh_a, mesh_b, {"whole": (None, None), "heightfield": heightfield_filters(*mesh_a)},
                                  samples=samples, seed=0)


@pytest.mark.parametrize("name", list(encoder_gains.VARIANTS))
def test_every_encoder_gains_variant_writes_a_file_the_unchanged_decoder_reads(name):
    """benchmarks/encoder_gains.py's variants change the encoder alone: each file of a rough
    generated surface decodes (constants as they are) within its RMS target, and a band-ratio
    variant's steps line holds one step per band, each coarser level's about ``ratio`` times
    the next finer one's, as today's decoder expands it."""
    import mzc
    from mzc.codecs import dwt2d

    rng = np.random.default_rng(5)
    z = rng.normal(scale=0.3, size=(70, 90)).cumsum(axis=0).cumsum(axis=1) / 20
    grid = ZGrid(z, 1.0, 1.0)
    _what, constants, options, ratio = encoder_gains.VARIANTS[name]
    with encoder_gains.encoder_of(constants, ratio):
        data = mzc.encode(grid, "dwt2d", rmse=0.05, **options)
    decoded = mzc.decode(data)
    assert np.sqrt(np.mean(np.square(decoded.z - z))) <= 0.05 * 1.5   # the target is a surface RMS
    steps = [float(v) for v in header_fields(data)["steps"]]
    levels = options.get("level", dwt2d.w2.default_levels(grid.shape, dwt2d.w2.TRANSFORMS[dwt2d.VERSION[0]].coarsest))
    assert len(steps) == (2 if ratio is None else 1 + 3 * levels)
    expanded = dwt2d.expand_steps(steps, 1 + 3 * levels)
    if ratio is not None:
        np.testing.assert_allclose(np.array(expanded[1:-3]) / np.array(expanded[4:]), ratio, rtol=1e-3)


def test_codec_limits_rebuilds_as_the_decoder_and_finds_the_axis_of_a_symmetric_surface():
    """benchmarks/codec_limits.py's studies stand on two pieces of their own: its reconstruction
    with no offset is the decoder's, node for node, on a rough generated surface (so an offset's
    figure is the decoder's own with that one change), and the mirror axis it finds on a surface
    symmetric about column 40 (with a lopsided mask) is that column, with no asymmetry."""
    import mzc
    from mzc.codecs import dwt2d

    rng = np.random.default_rng(7)
    z = rng.normal(scale=0.3, size=(70, 90)).cumsum(axis=0).cumsum(axis=1) / 20
    z[:8, :5] = np.nan
    grid = ZGrid(z, 1.0, 1.0)
    data = mzc.encode(grid, "dwt2d", rmse=0.05)
    prepared = dwt2d.Prepared(grid, dwt2d.DEFAULT_WAVELET, None, dwt2d.SLOPE_LIMIT)
    step = codec_limits.file_step(data, grid)
    qflat, _ = prepared.decoded(step)
    rebuilt = codec_limits.offset_decoded(prepared, qflat, step, 0.0)
    np.testing.assert_array_equal(rebuilt[grid.valid], mzc.decode(data).z[grid.valid])
    assert not np.array_equal(codec_limits.offset_decoded(prepared, qflat, step, 0.1)[grid.valid],
                              rebuilt[grid.valid])
    columns = np.arange(81)
    symmetric = np.tile(np.cos((columns - 40) / 9.0) * 5, (30, 1)) + np.arange(30)[:, None] * 0.1
    symmetric[:, 75:] = np.nan   # a mask that is not symmetric: the axis is found where both sides are valid
    twice, asymmetry = codec_limits.mirror_axis(ZGrid(symmetric, 1.0, 1.0))
    assert (twice, asymmetry) == (80, 0.0)


def test_a_face_against_itself_is_zero():
    from mzc.meshes import read_mesh

    mesh = read_mesh(face_path("f18.ply"))
    result = parts_of((mesh.points, mesh.triangles), (mesh.points, mesh.triangles))
    for part in ("whole", "heightfield"):
        assert result[part]["rms"] < 1e-9 and result[part]["hausdorff"] < 1e-9


def test_a_shift_of_a_tenth_in_z_measures_a_tenth_on_flat_parts():
    result = parts_of(flat_mesh(), flat_mesh(0.1))
    for part in ("whole", "heightfield"):
        assert result[part]["rms"] == pytest.approx(0.1, rel=1e-9)
        assert result[part]["hausdorff"] == pytest.approx(0.1, rel=1e-9)


def test_the_heightfield_part_leaves_out_steep_and_hidden_triangles():
    keep_flat, _ = heightfield_filters(*flat_mesh())
    keep_wall, _ = heightfield_filters(*wall_mesh())
    assert keep_flat(None, np.arange(10)).all()
    assert not keep_wall(None, np.arange(2)).any()
    lower, upper = flat_mesh(), flat_mesh(5.0)
    stacked = (np.vstack([lower[0], upper[0]]), np.vstack([lower[1], upper[1] + len(lower[0])]))
    keep, keep_b = heightfield_filters(*stacked)
    hidden = keep(None, np.arange(len(stacked[1])))
    assert not hidden[:len(lower[1])].any() and hidden[len(lower[1]):].all()
    # B's samples count where their nearest triangle of A does: above the upper patch, not under the lower
    assert keep_b(np.array([[20, 15, 6.0], [20, 15, 2.4], [20, 15, 2.6], [20, 15, -1.0]]), None).tolist() == \
        [True, False, True, False]


def test_parts_equal_separate_surface_distance_calls():
    grid = ZGrid(0.05 * np.random.default_rng(1).random((31, 41)), 1.0, 1.0)
    mesh_a, mesh_b = flat_mesh(), contenders.mesh_pair(grid)
    filters = heightfield_filters(*mesh_a)
    parts = surface_distance_parts(mesh_a, mesh_b, {"whole": (None, None), "hf": filters}, samples=3000, seed=4)
    assert parts["whole"] == surface_distance(mesh_a, mesh_b, samples=3000, seed=4)
    assert parts["hf"] == surface_distance(mesh_a, mesh_b, samples=3000, seed=4, keep_a=filters[0], keep_b=filters[1])


def test_diff_heightfield_reports_both_parts(tmp_path):
    mesh_a, mesh_b = flat_mesh(), flat_mesh(0.1)
    paths = []
    for name, (points, triangles) in {"a.obj": mesh_a, "b.obj": mesh_b}.items():
        lines = [f"v {x} {y} {z}" for x, y, z in points] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in triangles]
        (tmp_path / name).write_text("\n".join(lines) + "\n")
        paths.append(tmp_path / name)
    result = run_mzc("diff", *paths, "--heightfield", "--samples", "2000", "--json", check=True)
    report = json.loads(result.stdout)
    assert report["surface_rms"] == pytest.approx(0.1, rel=1e-6)
    assert report["surface_heightfield_rms"] == pytest.approx(0.1, rel=1e-6)


# --------------------------------------------------------------------------- grid peers


def central_grid():
    """A small spherical grid of a bumpy patch about 100 mm from its centre, with a hole and a
    turned, shifted frame: everything the peers' container must carry."""
    rows, cols = np.mgrid[0:48, 0:64]
    z = 100.0 + 3.0 * np.sin(cols / 7.0) * np.cos(rows / 5.0) + 0.02 * rows
    z[20:26, 30:37] = np.nan
    turn = np.array([[np.cos(0.3), 0.0, np.sin(0.3)], [0.0, 1.0, 0.0], [-np.sin(0.3), 0.0, np.cos(0.3)]])
    return ZGrid(z, 0.5, 0.5, origin=(-16.0, -12.0), transform=np.hstack([turn, [[1.0], [-17.0], [-97.0]]]),
                 projection="spherical", radius=104.5)


def node_errors(grid, mesh):
    """Distances between the nodes of ``grid``'s mesh and those of a decoded ``mesh`` (same
    connectivity): for a central grid, the error of each node's value along its ray."""
    points, triangles = contenders.mesh_pair(grid)
    np.testing.assert_array_equal(mesh[1], triangles)
    return np.linalg.norm(mesh[0] - points, axis=1)


def peer(name):
    """The grid peer ``name`` of the benchmark table, skipping when its codec is not installed."""
    table, missing = contenders.all_contenders()
    found = [c for c in table if c.name == name]
    if not found:
        pytest.skip(f"{name} not available: {missing}")
    return found[0]


@pytest.mark.parametrize("projection", ["spherical", "planar"])
def test_the_grid_container_rebuilds_the_grid_it_was_given(projection):
    grid = central_grid()
    if projection == "planar":
        grid = grid.with_z(grid.z, projection="planar", radius=None)
    data = contenders.grid_file(grid, b"payload", extra=b"xy")
    mask = contenders.mask_bytes(grid.valid)
    assert len(data) == contenders.GRID_HEADER.size + 2 + 4 + len(mask) + len(b"payload")
    decoded, extra, valid, payload = contenders.read_grid_file(data, extra_size=2)
    assert (extra, payload) == (b"xy", b"payload")
    np.testing.assert_array_equal(valid, grid.valid)
    assert (decoded.shape, decoded.d1, decoded.d2, decoded.origin) == (grid.shape, grid.d1, grid.d2, grid.origin)
    assert (decoded.projection, decoded.radius) == (grid.projection, grid.radius)
    np.testing.assert_array_equal(decoded.transform, grid.transform)
    assert node_errors(grid, contenders.masked_mesh(decoded, grid.z, valid)).max() == 0.0


def test_the_container_header_holds_projection_and_radius_in_nine_bytes():
    assert contenders.GRID_HEADER.size == 2 * 4 + 16 * 8 + 1 + 8


@pytest.mark.parametrize("bound", [0.01, 0.05, 0.5])
def test_sperr_keeps_its_point_wise_bound_on_a_central_grid(bound):
    sperr, grid = peer("SPERR"), central_grid()
    data = sperr.encode(grid, bound, 1.0)
    assert node_errors(grid, sperr.decode(data)).max() <= bound * (1 + 1e-9)


def test_sperr_psnr_gets_smaller_errors_for_more_bytes_at_higher_targets():
    sperr, grid = peer("SPERR psnr"), central_grid()
    runs = [(len(data), node_errors(grid, sperr.decode(data))) for data in
            (sperr.encode(grid, psnr, 1.0) for psnr in (40, 60, 80))]
    sizes = [size for size, _ in runs]
    rms = [np.sqrt(np.mean(errors**2)) for _, errors in runs]
    assert sizes == sorted(sizes) and rms == sorted(rms, reverse=True)
    assert rms[-1] < 1e-3


@pytest.mark.parametrize("step", [0.05, 0.5])
def test_htj2k_errors_stay_below_half_its_step_on_a_central_grid(step):
    htj2k, grid = peer("HTJ2K"), central_grid()
    errors = node_errors(grid, htj2k.decode(htj2k.encode(grid, step, 1.0)))
    assert 0 < np.sqrt(np.mean(errors**2)) < step / 2


def test_htj2k_refuses_steps_its_encoder_would_not_honour():
    htj2k, grid = peer("HTJ2K"), central_grid()
    with pytest.raises(contenders.NotApplicable):
        htj2k.encode(grid, 1e-6, 1.0)   # imagecodecs would turn this into lossless coding


# --------------------------------------------------------------------------- summary ratios


def power_law_result():
    """An item where a peer costs exactly twice mzc's bytes at equal whole-surface RMS and
    Hausdorff, and half at equal height-field RMS (bytes = k / error on every curve)."""
    def point(family, name, bytes_, whole, hausdorff, heightfield):
        return {"family": family, "contender": name, "setting": bytes_, "bytes": bytes_,
                "whole": {"rms": whole, "hausdorff": hausdorff}, "heightfield": {"rms": heightfield}}

    errors = (0.05, 0.1, 0.2, 0.4)
    points = [point("mzc", "mzc a", 1000 / e, e, 10 * e, e) for e in errors]
    points += [point("mzc", "mzc b", 5000 / e, e, 10 * e, e) for e in errors]   # never mzc's best
    points += [point("peer", "p", 2000 / e, e, 10 * e, e / 4) for e in errors]
    points.append(point("peer", "p", 1e6, 0.3, 3.0, 0.3))   # dominated: off the Pareto front
    return {"corpus": "c", "unit": 1.0, "points": points}


def test_item_ratios_interpolate_the_chosen_measure():
    result = power_law_result()
    assert report.item_ratios(result, (0.1, 0.2), "whole rms")["p"] == pytest.approx([2.0, 2.0])
    assert report.item_ratios(result, (1.0, 2.0), "whole hausdorff")["p"] == pytest.approx([2.0, 2.0])
    hf = report.item_ratios(result, (0.05, 0.2), "heightfield rms")["p"]
    assert hf[0] == pytest.approx(0.5) and hf[1] is None   # the peer's height-field errors stop at 0.1


def test_summary_ratios_keep_the_measures_in_the_given_order():
    targets = {"whole rms": (0.1,), "whole hausdorff": (1.0,), "heightfield rms": (0.1,)}
    ratios = report.summary_ratios([power_law_result()] * 2, targets)
    assert list(ratios) == list(targets)
    assert ratios["whole rms"]["c"]["p"][0] == (pytest.approx(2.0), 2)
    assert ratios["heightfield rms"]["c"]["p"][0] == (pytest.approx(0.5), 2)


def test_parts_of_one_item_join_in_order_with_summed_clocks():
    fields = {"corpus": "c", "item": "i"}
    parts = [{"fields": fields, "points": [{"contender": name}], "timing": {name: {}}, "failures": [],
              "skipped": [], "clock": {"load": 1.0, "metric": 2.0}} for name in ("a", "b")]
    results = {}
    for part in parts:
        rd.add_part(results, part)
    assert [p["contender"] for p in results["i"]["points"]] == ["a", "b"]
    assert set(results["i"]["timing"]) == {"a", "b"}
    assert results["i"]["clock"] == {"load": 2.0, "metric": 4.0}


# --------------------------------------------------------------------------- the quick run


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """benchmarks/rd.py --quick on one face, run once for the tests below."""
    for package in ("DracoPy", "pysz", "zfpy", "lerc", "imagecodecs"):
        pytest.importorskip(package)
    face_path("f18.ply")
    out = tmp_path_factory.mktemp("rd")
    subprocess.run([sys.executable, str(BENCHMARK), "--quick", "--faces", "1", "--out", str(out)],
                   check=True, capture_output=True, timeout=300)
    return out


def test_quick_run_writes_report_plot_and_json(quick_run):
    assert (quick_run / "rd-results.md").read_text().startswith("# mzc rate-distortion benchmark")
    assert (quick_run / "rd-faces.png").stat().st_size > 10_000
    document = json.loads((quick_run / "rd-results.json").read_text())
    points = [p for item in document["items"] for p in item["points"]]
    names = {c.name for c in contenders.all_contenders()[0]}
    assert {"mzc dwt2d", "Draco", "SZ3", "zfp", "LERC", "xz OBJ", "JPEG 2000"} <= names
    assert {p["contender"] for p in points} == names   # every contender of the table ran
    assert all(p["bytes"] > 0 and np.isfinite(p["whole"]["rms"]) and np.isfinite(p["heightfield"]["rms"])
               for p in points)


def test_quick_run_puts_the_whole_surface_first(quick_run):
    document = json.loads((quick_run / "rd-results.json").read_text())
    assert list(document["summary_ratios"]) == ["whole rms", "whole hausdorff", "heightfield rms"]
    text = (quick_run / "rd-results.md").read_text()
    assert text.index("at equal whole-surface RMS") < text.index("at equal whole-surface Hausdorff") \
        < text.index("at equal height-field RMS")
    assert "| SZ3 |" in text and "| Draco |" in text


def test_grid_peers_decode_the_central_face_grid_to_its_floor(quick_run):
    """The peers' finest settings come within 10% of the lossless z-grid over the whole face:
    their files rebuild the same central grid."""
    document = json.loads((quick_run / "rd-results.json").read_text())
    face = document["items"][0]
    assert face["grid_projection"] == "spherical"
    best = {}
    for p in face["points"]:
        best[p["contender"]] = min(best.get(p["contender"], np.inf), p["whole"]["rms"])
    floor = best["mzc zgrid (lossless)"]
    grid_peers = [c.name for c in contenders.all_contenders()[0] if c.family == "peer" and c.source == "grid"]
    assert {"SZ3", "LERC", "zfp", "JPEG 2000"} <= set(grid_peers)
    for name in grid_peers:
        assert best[name] < 1.1 * floor, name


def test_draco_at_14_bits_beats_draco_at_8_bits(quick_run):
    document = json.loads((quick_run / "rd-results.json").read_text())
    face = document["items"][0]
    draco = {p["setting"]: p for p in face["points"] if p["contender"] == "Draco"}
    for part in ("whole", "heightfield"):
        assert draco[14][part]["rms"] < draco[8][part]["rms"] / 10
    assert draco[14]["bytes"] > draco[8]["bytes"]


# --------------------------------------------------------------------------- the speed benchmark

SPEED = REPO / "benchmarks" / "speed.py"
SPEED_SECTIONS = ("# mzc speed benchmark", "## Done-when checks", "## Method",
                  "## Start-up and the five-filter pipeline", "## Every stage on f18",
                  "## Beside Draco, JPEG 2000 and SPERR", "## Scaling")


@pytest.fixture(scope="module")
def speed_run(tmp_path_factory):
    """benchmarks/speed.py --quick into a temporary folder, run once for the tests below."""
    for package in ("DracoPy", "imagecodecs"):
        pytest.importorskip(package)
    face_path("f18.ply")
    return quick_report(SPEED, "speed", tmp_path_factory)


def quick_report(script, stem, tmp_path_factory):
    """(the text of STEM-results.md, its JSON) of ``script --quick`` run into a temporary folder."""
    out = tmp_path_factory.mktemp(stem)
    subprocess.run([sys.executable, str(script), "--quick", "--out", str(out)], check=True, capture_output=True,
                   timeout=120)
    return (out / f"{stem}-results.md").read_text(), json.loads((out / f"{stem}-results.json").read_text())


def test_speed_report_has_every_section_and_a_verdict_per_check(speed_run):
    text, document = speed_run
    positions = [text.index(section) for section in SPEED_SECTIONS]
    assert positions == sorted(positions)
    assert len(document["checks"]) == 15   # 2 pipeline, 2 Draco, 3 memory, 4 exponents (quick: one grid), LAZ, 3 diffs
    for label, _measured, _ok in document["checks"]:
        assert f"| {label} |" in text
    assert document["commit"] and len(document["load"]) == 4


def test_speed_figures_are_positive_numbers(speed_run):
    _, document = speed_run
    cli = document["cli"]
    for row in ("python -c pass", 'python -c "import numpy"', "mzc --help", "pipeline default",
                "default: slice", "default: encode", "default: decode", "default: densify -n 3",
                "default: triangulate"):
        assert cli[row]["ok"] == cli[row]["runs"] >= 1, (row, cli[row]["error"])
        assert cli[row]["median_s"] > 0 and cli[row]["peak_mb"] > 0
    assert all(row["median_s"] > 0 and row["min_s"] > 0 for row in document["api"].values())
    assert {"Draco: encode", "Draco: decode", "default: encode", "default: decode", "default: SPERR encode",
            "default: JPEG 2000 lossless decode"} <= set(document["api"])
    assert all(fact["bytes"] > 0 for fact in document["facts"].values())
    rows = document["scaling"]
    assert len(rows) == 2 * 4
    assert all(r["status"] == "ok" and r["wall_s"] > 0 and r["cpu_s"] > 0 and r["peak_mb"] > 0 for r in rows)


def test_speed_records_a_failed_stage_as_a_row():
    import speed

    timeout = speed.run_command([sys.executable, "-c", "import time; time.sleep(30)"], timeout=0.5)
    assert timeout["status"] == "timeout" and timeout["wall_s"] < 10
    memory = speed.run_command([sys.executable, "-c", "import numpy; numpy.ones(2 * 10**9)"], memory_cap=1e9)
    assert memory["status"] == "out of memory", memory
    failed = speed.run_command([sys.executable, "-c", "raise SystemExit('no')"])
    assert failed["status"] == "failed" and "no" in failed["error"]
    ok = speed.run_command([sys.executable, "-c", "import numpy; numpy.ones(10**8)"])
    assert ok["status"] == "ok" and 700 < ok["peak_mb"] < 1200   # the child's own 800 MB, not this process's


def test_the_terrain_is_a_seeded_grid_with_a_border_and_holes():
    import scaling
    import speed

    grid = scaling.terrain_grid(300, 400, 3)
    assert grid.shape == (300, 400) and np.array_equal(grid.z, scaling.terrain_grid(300, 400, 3).z, equal_nan=True)
    assert 0.5 < grid.valid.mean() < 0.8 and grid.valid[150, 200] and not grid.valid[0, 0]
    assert speed.grid_shape(25.0) == (4472, 5590)


# --------------------------------------------------------------------------- the web decode benchmark

WEB_DECODE = REPO / "benchmarks" / "web_decode.py"


def web_decode(out, *args, env=None):
    """benchmarks/web_decode.py ARGS --out OUT as a finished process."""
    return subprocess.run([sys.executable, str(WEB_DECODE), *args, "--out", str(out)], capture_output=True, text=True,
                          timeout=300, env=env)


def test_web_decode_times_web_and_draco_on_f18_in_one_node_process(tmp_path):
    from mzc.meshes import read_mesh

    pytest.importorskip("DracoPy")
    mesh = read_mesh(face_path("f18.ply"))
    result = web_decode(tmp_path, "--runs", "3", "--warmups", "1")
    assert result.returncode == 0, result.stderr
    if "skipped" in result.stderr:
        pytest.skip(result.stderr.strip())
    document = json.loads((tmp_path / "web-decode-results.json").read_text())
    text = (tmp_path / "web-decode-results.md").read_text()
    assert document["draco_mesh"] == {"vertices": len(mesh.points), "triangles": len(mesh.triangles)}
    grid = document["grid"]
    assert grid["version"] == "7.0" and 0 < grid["valid"] < grid["rows"] * grid["cols"]
    for name in ("mzc", "draco"):
        times = document[name]
        assert 0 < times["wall_min_ms"] <= times["wall_median_ms"]
        assert 0 <= times["cpu_min_ms"] <= times["cpu_median_ms"]
    assert document["ratio_wall"] == document["mzc"]["wall_median_ms"] / document["draco"]["wall_median_ms"]
    assert 0 < document["files"]["mzc"] < document["files"]["draco"]
    sizes = document["sizes"]
    assert sizes["draco_wasm_gzip"] > 0 and sizes["draco_js_gzip"] > 0
    if sizes["esbuild"]:
        assert 0 < sizes["gzip"] < sizes["minified"] < sizes["written"]
        assert f"**{sizes['gzip']:,}**" in text
    assert f"{document['ratio_wall']:.2f}x in wall time" in text and len(document["load_before"]) == 3


def test_web_decode_skips_with_a_message_without_draco3d_or_node(tmp_path):
    empty = tmp_path / "node_modules"
    empty.mkdir()
    out = tmp_path / "out"
    no_draco = web_decode(out, "--modules", str(empty))
    assert no_draco.returncode == 0 and no_draco.stderr.startswith("web_decode: skipped: draco3d is not in")
    no_node = web_decode(out, "--modules", str(empty), env={**os.environ, "PATH": str(empty)})
    assert no_node.returncode == 0 and no_node.stderr == "web_decode: skipped: node is not installed\n"
    assert not out.exists()


# --------------------------------------------------------------------------- the whole-object benchmark

OBJECTS = REPO / "benchmarks" / "objects.py"
import objects  # noqa: E402


def oriented_plane(spacing=1.0, size=20):
    """A flat square cloud in z = 0 on a lattice of ``spacing``, normals +z."""
    xy = np.mgrid[0:size, 0:size].reshape(2, -1).T * spacing
    points = np.column_stack([xy, np.zeros(len(xy))])
    return objects.Surface(points, np.zeros((0, 3), dtype=np.int64), np.tile([0.0, 0.0, 1.0], (len(points), 1)))


def test_on_two_meshes_the_distances_are_those_of_surface_distance_parts():
    from mzc.measure.metrics import distance_summary

    grid = ZGrid(0.05 * np.random.default_rng(1).random((31, 41)), 1.0, 1.0)
    mesh_a, mesh_b = flat_mesh(), contenders.mesh_pair(grid)
    ours = distance_summary(*objects.directed(objects.Surface(*mesh_a), objects.Surface(*mesh_b), 3000, 4))
    assert ours == surface_distance_parts(mesh_a, mesh_b, {"whole": (None, None)}, samples=3000, seed=4)["whole"]


def test_errors_are_in_percent_of_the_diagonal_with_the_coverage_of_the_original():
    flat = objects.Surface(*flat_mesh())
    diagonal = np.hypot(40, 30)
    near = objects.errors(flat, objects.Surface(*flat_mesh(0.0005 * diagonal)), 2000)   # 0.05% of D away
    assert near["whole"]["rms"] == pytest.approx(0.05) and near["whole"]["hausdorff"] == pytest.approx(0.05)
    assert near["coverage"] == 100 and near["missed"] == near["spurious"] == near["far_share"] == 0
    far = objects.errors(flat, objects.Surface(*flat_mesh(0.002 * diagonal)), 2000)   # 0.2% of D away
    assert far["coverage"] == 0 and far["missed"] == 0 and far["spurious"] == far["far_share"] == 100
    # half the original missing from the rebuild: the uncovered half is beyond reach
    points, triangles = flat_mesh()
    half = triangles[points[triangles].mean(axis=1)[:, 0] < 20]
    missing = objects.errors(flat, objects.Surface(points, half), 4000)
    assert 45 < missing["coverage"] < 55 and 35 < missing["missed"] < 50 and missing["spurious"] == 0


def test_a_plane_measures_zero_against_its_own_oriented_cloud_and_its_offset_beside_it():
    cloud = oriented_plane()
    inside = np.array([[3.5, 7.25, 0.0], [10.1, 2.9, 0.3], [9.0, 9.0, -0.2]])
    assert objects.disc_distances(cloud, inside) == pytest.approx([0.0, 0.3, 0.2])
    # beyond the cloud's edge the discs end: 2 past the last column (x = 19), whose discs reach 1 (the spacing)
    assert objects.disc_distances(cloud, np.array([[21.0, 10.0, 0.0]]))[0] == pytest.approx(1.0)
    # a point's nearest point overstates the distance to the surface by up to half the spacing
    assert objects.distance_to(objects.Surface(cloud.points, cloud.triangles), inside)[0] == pytest.approx(
        np.hypot(0.5, 0.25))


def test_a_cloud_original_is_measured_by_its_points_and_its_discs():
    points, triangles = flat_mesh()   # 0..40 x 0..30, spacing 1
    cloud = oriented_plane()          # 0..19 x 0..19 inside it
    result = objects.errors(cloud, objects.Surface(points, triangles), 3000)
    assert result["coverage"] == 100 and result["whole"]["a_to_b_rms"] == 0   # every point lies on the mesh
    assert 60 < result["spurious"] < 80   # the mesh's area outside the cloud's


def test_splitting_triangles_at_their_centroids_keeps_the_surface():
    from mzc.measure.metrics import triangle_areas

    surface = objects.Surface(*flat_mesh())
    bigger = objects.with_vertices(surface, len(surface.points) + 100)
    assert len(bigger.points) == len(surface.points) + 100
    assert len(bigger.triangles) == len(surface.triangles) + 200
    assert triangle_areas(bigger.points, bigger.triangles).sum() == pytest.approx(40 * 30)
    assert objects.input_facts(bigger)["boundary_edges"] == objects.input_facts(surface)["boundary_edges"]


def test_input_facts_weld_a_triangle_soup():
    points, triangles = flat_mesh()
    soup = objects.Surface(points[triangles].reshape(-1, 3), np.arange(3 * len(triangles)).reshape(-1, 3))
    facts = objects.input_facts(soup)
    assert facts["vertices"] == 3 * len(triangles) and facts["distinct_positions"] == len(points)
    assert (facts["boundary_edges"], facts["non_manifold_edges"], facts["parts"]) == (2 * (40 + 30), 0, 1)


@pytest.fixture(scope="module")
def objects_run(tmp_path_factory):
    """benchmarks/objects.py --quick (the armadillo, the hand and f18), run once for the tests below."""
    pytest.importorskip("DracoPy")
    for name in objects.QUICK_OBJECTS:
        if not any((objects.OBJECTS / f"{name}{suffix}").is_file() for suffix in (".ply", ".obj")):
            pytest.skip(f"shared object data not available ({objects.OBJECTS / name})")
    face_path("f18.ply")
    out = tmp_path_factory.mktemp("objects")
    subprocess.run([sys.executable, str(OBJECTS), "--quick", "--out", str(out)], check=True, capture_output=True,
                   timeout=300)
    return out, json.loads((out / "objects-results.json").read_text())


def test_objects_quick_run_writes_every_field(objects_run):
    out, document = objects_run
    assert (out / "objects-results.md").read_text().startswith("# mzc whole-object benchmark (issue 28)")
    assert (out / "objects-rd.png").stat().st_size > 10_000
    assert {"settings", "machine", "commit", "versions", "missing", "calibration", "summary", "verdicts", "speed",
            "items"} <= set(document)
    assert document["settings"]["errors_in"] == "% of D"
    assert [(item["group"], item["item"]) for item in document["items"]] == \
        [("scanned", "armadillo"), ("scanned", "hand"), ("faces", "f18")]
    for item in document["items"]:
        assert {"diagonal", "facts", "grid", "floor", "points", "failures", "warnings"} <= set(item)
        assert not item["failures"]
        for point in [item["floor"], *item["points"]]:
            assert {"rms", "mean", "hausdorff", "a_to_b_rms", "b_to_a_rms"} <= set(point["whole"])
            assert {"coverage", "missed", "spurious", "far_share"} <= set(point)
            assert 0 <= point["coverage"] <= 100 and np.isfinite(point["whole"]["rms"])
        assert {p["contender"] for p in item["points"]} == {objects.MZC, objects.MZC_SURFACE, objects.DRACO}
        # the surface given to encode comes back within a whole-surface target its default grid's floor leaves
        # room for (the run's fewer samples aside)
        assert all(p["whole"]["rms"] <= 1.1 * p["setting"] for p in item["points"]
                   if p["contender"] == objects.MZC_SURFACE and p["setting"] > 1.25 * item["floor"]["whole"]["rms"])
        assert all(p["bytes"] > 0 for p in item["points"])
    assert set(document["speed"]) == {"armadillo", "hand"}
    assert all(row["slice_encode"]["wall_s"] > 0 and row["draco_decode"]["wall_s"] > 0
               for row in document["speed"].values())


def test_objects_quick_run_errors_are_percent_of_the_diagonal(objects_run):
    """Draco's quantisation error is a fixed share of the box whatever the object's units: its
    ladder spans the issue's 0.05-0.1% D from 6 to 14 bits on the hand, the armadillo (a cloud,
    in other units) and the face (mm)."""
    _, document = objects_run
    for item in document["items"]:
        draco = {p["setting"]: p["whole"]["rms"] for p in item["points"] if p["contender"] == objects.DRACO}
        assert draco[14] < 0.01 < 0.1 < draco[6], (item["item"], draco)
        assert draco[14] < draco[10] < draco[6]
    face = document["items"][-1]   # in mm: its default grid rebuilds it within 0.05 mm RMS, all of it
    assert 0.005 < face["floor"]["whole"]["rms"] * face["diagonal"] / 100 < 0.05
    assert face["floor"]["coverage"] > 95


def test_objects_quick_run_gives_a_verdict_or_a_reason_for_every_figure(objects_run):
    out, document = objects_run
    text = (out / "objects-results.md").read_text()
    figures = {row["figure"] for row in document["verdicts"]}
    assert {"floor RMS", "floor Hausdorff", f"area within {objects.NEAR}% D"} <= figures
    for row in document["verdicts"]:
        assert row["ok"] in (True, False, None)
        assert row["ok"] or row["reason"], row   # a miss or an n/a says why
        assert f"| {row['figure']} | {row['item']} |" in text
    assert document["summary"]["mm"]["faces"]["Draco"][0][1] == 1   # the face's 0.05 mm ratio counted


# --------------------------------------------------------------------------- the chart-spacing benchmark

CHART_SPACING = REPO / "benchmarks" / "chart_spacing.py"


def test_chart_spacing_quick_run_measures_each_spacing_against_the_former_default(tmp_path):
    """benchmarks/chart_spacing.py --quick (the dragon and the hand at 1, 2 and 4 times the
    source's spacing, and the default): each grid's floor and dwt2d ladder in % of D, coarser
    spacings with fewer nodes and a larger floor error, and the hand's default coarser than the
    former one (k = 1) yet meeting the floor figures that one meets, in fewer bytes at 0.1% D."""
    for name in ("dragon", "hand"):
        if not (objects.OBJECTS / f"{name}.ply").is_file():
            pytest.skip(f"shared object data not available ({objects.OBJECTS / name})")
    subprocess.run([sys.executable, str(CHART_SPACING), "--quick", "--out", str(tmp_path)], check=True,
                   capture_output=True, timeout=300)
    document = json.loads((tmp_path / "chart-spacing-results.json").read_text())
    assert document["format"].startswith("mzc-dwt2d ")
    assert (tmp_path / "chart-spacing-results.md").read_text().startswith("# Multi-chart grid spacing")
    for item in document["items"]:
        rows = item["rows"]
        assert list(rows) == ["1", "2", "4", "default"]
        assert rows["1"]["d1"] == pytest.approx(item["s0"]) and rows["4"]["d1"] == pytest.approx(4 * item["s0"])
        assert rows["1"]["nodes"] > rows["2"]["nodes"] > rows["4"]["nodes"]
        assert rows["1"]["floor"]["whole"]["rms"] < rows["4"]["floor"]["whole"]["rms"]
        for row in rows.values():
            assert [p["setting"] for p in row["points"]] == list(document["settings"]["ladder"])
            assert all(p["bytes"] > 0 and 0 < p["whole"]["rms"] < 1 for p in row["points"])
    hand = next(item for item in document["items"] if item["item"] == "hand")["rows"]
    former, default = hand["1"]["figures"], hand["default"]["figures"]
    assert hand["default"]["nodes"] < hand["1"]["nodes"]
    assert all(default["floor_met"][name] for name, met in former["floor_met"].items() if met)
    assert default["mzc_bytes"][1] < former["mzc_bytes"][1]


# --------------------------------------------------------------------------- the DEM benchmark

DEMS = REPO / "benchmarks" / "dems.py"


@pytest.fixture(scope="module")
def dems_run(tmp_path_factory):
    """benchmarks/dems.py --quick (the SRTM tile and the float kootenai grid) into a temporary folder."""
    for package in ("rasterio", "lerc", "imagecodecs"):
        pytest.importorskip(package)
    return quick_report(DEMS, "dems", tmp_path_factory)


def test_dems_every_contender_keeps_the_max_error_it_was_asked_for(dems_run):
    text, document = dems_run
    assert text.startswith("# mzc dwt2d beside LERC and SPERR on public DEMs")
    assert [item["dem"] for item in document["items"]] == ["srtm_blurred_res", "kootenai"]
    for item in document["items"]:
        for row in item["max_error"]:
            assert [p["contender"] for p in row["points"]] == ["mzc dwt2d", "LERC GeoTIFF", "SPERR"]
            for p in row["points"]:
                assert p["valid"]["max"] <= row["target"] * (1 + 1e-9) and p["valid"]["mask"], (item["dem"], p)
                assert 0 < p["payload"] < p["bytes"]
            mzc, lerc, sperr = (p["valid"]["integers"] for p in row["points"])
            assert (mzc, lerc, sperr) == ((True, True, False) if item["sample"] == "int16" else (False,) * 3)


def test_dems_peers_are_compared_at_the_rmse_mzc_measured(dems_run):
    _, document = dems_run
    for item in document["items"]:
        for row in item["rmse"]:
            assert row["measured"] == row["mzc"]["valid"]["rms"]
            assert abs(row["measured"] / row["target"] - 1) < 0.1
            sperr = row["peers"]["SPERR"]   # SPERR's bound moves its RMSE smoothly: its search lands
            assert abs(sperr["nearest"]["valid"]["rms"] / row["measured"] - 1) <= 0.02
    for size in ("bytes", "payload"):
        for kind in ("max_error", "rmse"):
            for per in document["summary"][size][kind].values():
                assert all(g > 0 and n == 2 for g, n in per)
