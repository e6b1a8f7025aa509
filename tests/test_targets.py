"""A mesh or cloud given to encode: with dwt2d's rmse it is cut at the spacing that codes it within
that RMS error over its whole surface in the fewest bytes (mzc.targets); else as slice cuts it."""

import numpy as np
import pytest
from test_charts import torus

import mzc
from mzc import targets
from mzc.measure.metrics import surface_distance
from mzc.samples import blob

from conftest import run_mzc, shared_object


def diagonal(mesh):
    return float(np.linalg.norm(np.ptp(mesh.points, axis=0)))


def whole_error(mesh, data):
    """The symmetric RMS distance between ``mesh`` and the mesh of the grid ``data`` holds, every node kept."""
    rebuilt = mzc.triangulate(mzc.decode(data), vertices="all")
    return surface_distance((mesh.points, mesh.triangles), (rebuilt.points, rebuilt.triangles))["rms"]


@pytest.mark.parametrize("share", [0.05, 0.1])
def test_a_closed_object_coded_for_a_whole_surface_rmse_is_within_it_in_fewer_bytes(share):
    """The torus (charts, generated): within the target over its whole surface, at a coarser
    spacing than the default, in at most 0.7 of the bytes of its default grid coded at the same
    rmse (measured: 1,721 and 1,038 bytes where 2,747 and 2,057)."""
    mesh = torus()
    target = share * diagonal(mesh) / 100
    data, default = mzc.encode(mesh, rmse=target), mzc.slice(mesh)
    assert whole_error(mesh, data) <= target
    assert mzc.decode(data).d1 >= 2 * default.d1
    assert len(data) <= 0.7 * len(mzc.encode(default, rmse=target))


@pytest.mark.filterwarnings("ignore:not kept")   # the hand's vertex normals, recomputed
def test_the_hand_coded_for_0_1_percent_of_its_diagonal_is_within_it_in_fewer_bytes():
    """The closed scan of ../shared/data/objects: measured 1,934 bytes at 0.98 of the target where
    its default grid's file at the same rmse takes 2,874 at 0.91."""
    mesh = shared_object("hand.ply")
    target = 0.001 * diagonal(mesh)
    data = mzc.encode(mesh, rmse=target)
    assert whole_error(mesh, data) <= target
    assert len(data) <= 0.75 * len(mzc.encode(mzc.slice(mesh), rmse=target))


def test_a_target_below_every_coarser_floor_keeps_the_default_spacing():
    """At a millionth of the diagonal no coarser grid's floor passes: the blob keeps its default grid."""
    mesh = blob()
    target = 1e-6 * diagonal(mesh)
    grid = mzc.decode(mzc.encode(mesh, rmse=target))
    assert grid.d1 == mzc.slice(mesh).d1


def test_the_search_returns_the_coarsest_passing_factor_and_the_next_finer(monkeypatch):
    """Floors that grow with the spacing: the walk stops at the last factor whose floor is within
    FLOOR_SHARE of the target and offers the next finer one too; where FIRST fails it walks down,
    and where every factor fails it offers the default grid alone."""
    monkeypatch.setattr(targets, "whole_rms", lambda surface, grid: grid.d1)
    mesh = torus()
    default = mzc.slice(mesh).d1

    def factors(passing):
        grids = targets.sliced_for(mesh, passing * default / targets.FLOOR_SHARE)
        return [grid.d1 / default for grid, _ in grids]

    assert factors(4.1) == pytest.approx([4, 3])
    assert factors(9) == pytest.approx([8, 6])
    assert factors(1.7) == pytest.approx([1.5, 1])
    assert factors(0.5) == pytest.approx([1])


@pytest.mark.parametrize("options", [{"codec": "dct", "quality": 20}, {"max_error": 0.2}])
def test_without_rmse_a_mesh_is_coded_as_its_default_grid(options):
    """Any other codec or target: the same bytes as slicing first."""
    mesh = blob()
    assert mzc.encode(mesh, **options) == mzc.encode(mzc.slice(mesh), **options)


def test_a_mesh_with_a_prior_is_refused_in_one_line():
    with pytest.raises(mzc.MzcError, match="slice the surface with the prior first"):
        mzc.encode(blob(), prior=b"anything", rmse=0.1)


def test_encode_takes_a_mesh_file_on_the_command_line(tmp_path):
    """``mzc encode --rmse E a.obj`` codes the mesh within E over its whole surface; another target
    writes the bytes of ``mzc slice a.obj | mzc encode``; a prior beside a mesh is one line."""
    from mzc.meshes import write_mesh

    mesh = torus()
    path = tmp_path / "torus.obj"
    write_mesh(path, mesh)
    target = 0.001 * diagonal(mesh)
    run = run_mzc("encode", "--rmse", target, path, check=True)
    assert whole_error(mesh, run.stdout) <= target
    grid = run_mzc("slice", path, check=True).stdout
    assert run_mzc("encode", "--max-error", 0.05, path, check=True).stdout == \
        run_mzc("encode", "--max-error", 0.05, input=grid, check=True).stdout
    refused = run_mzc("encode", "--prior", path, "--rmse", target, path)
    assert refused.returncode != 0 and refused.stdout == b""
    assert len(refused.stderr.decode().strip().splitlines()) == 1
