"""The rate-distortion benchmark (benchmarks/rd.py): its metric on known cases, and a --quick run."""

import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO, face_path, run_mzc
from mzc.grid import ZGrid
from mzc.metrics import heightfield_filters, surface_distance, surface_distance_parts
from mzc.triangulation import grid_to_mesh

BENCHMARK = REPO / "benchmarks" / "rd.py"


def flat_mesh(shift=0.0):
    """A 40 x 30 mm flat patch at z = shift (1 mm grid)."""
    return grid_to_mesh(ZGrid(np.full((31, 41), shift), 1.0, 1.0))


def wall_mesh():
    """A vertical 10 x 10 mm wall in the plane y = 0 (its normals are horizontal)."""
    points = np.array([[0, 0, 0], [10, 0, 0], [0, 0, 10], [10, 0, 10]], dtype=float)
    return points, np.array([[0, 1, 2], [1, 3, 2]])


def parts_of(mesh_a, mesh_b, samples=4000):
    return surface_distance_parts(mesh_a, mesh_b, {"whole": (None, None), "heightfield": heightfield_filters(*mesh_a)},
                                  samples=samples, seed=0)


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
    keep, _ = heightfield_filters(*stacked)
    hidden = keep(None, np.arange(len(stacked[1])))
    assert not hidden[:len(lower[1])].any() and hidden[len(lower[1]):].all()


def test_parts_equal_separate_surface_distance_calls():
    mesh_a, mesh_b = flat_mesh(), grid_to_mesh(ZGrid(0.05 * np.random.default_rng(1).random((31, 41)), 1.0, 1.0))
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
    assert {"mzc dwt2d", "Draco", "SZ3", "zfp", "LERC", "xz OBJ"} <= {p["contender"] for p in points}
    assert all(p["bytes"] > 0 and np.isfinite(p["heightfield"]["rms"]) for p in points)


def test_draco_at_14_bits_beats_draco_at_8_bits(quick_run):
    document = json.loads((quick_run / "rd-results.json").read_text())
    face = document["items"][0]
    draco = {p["setting"]: p for p in face["points"] if p["contender"] == "Draco"}
    for part in ("whole", "heightfield"):
        assert draco[14][part]["rms"] < draco[8][part]["rms"] / 10
    assert draco[14]["bytes"] > draco[8]["bytes"]
