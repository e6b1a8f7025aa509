"""Shared priors (issue 33): ``mzc train``, ``slice/encode/decode --prior``, the formats of spec/prior.md.

The fixture and the spec's worked example decode as they always did; a grid coded against a prior
comes back within its bounds on generated surfaces, on random grids (hypothesis) and on the real
faces, leave-one-out (skipped when the shared data is absent); every refusal is one line.
"""

import hashlib
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mzc
from mzc.errors import MzcError
from mzc.formats import read_any, zgrid
from mzc.prior import PRIOR_MAGIC, RESIDUAL_MAGIC, prior_of, read_prior, residual_file

from codec_contract import FIXTURES, assert_same_grid
from conftest import FACE_NAMES, REPO, face_path, run_mzc

PRIOR_FIXTURES = FIXTURES / "prior"
SPEC = REPO / "spec" / "prior.md"


def bump(amplitude, tilt, shape=(24, 30), holes=False):
    """A generated bump (mm, spacing 1) as a mesh with a vertex at every node."""
    y, x = np.mgrid[0:shape[0], 0:shape[1]] * 1.0
    z = amplitude * np.exp(-((x - shape[1] / 2) ** 2 + (y - shape[0] / 2) ** 2) / 40) + tilt * x \
        + 0.3 * np.sin(x / 3) * np.cos(y / 4)
    if holes:
        z[:3, :4] = np.nan
        z[10:12, 12:15] = np.nan
    return mzc.triangulate(mzc.ZGrid(z, 1.0, 1.0, units="mm"), vertices="all")


@pytest.fixture(scope="module")
def trained():
    """A prior of four generated bumps."""
    return mzc.train([bump(8, 0.1), bump(9, 0.05), bump(7, 0.15), bump(8.5, 0.12)])


# --- the fixture and the spec's worked example --------------------------------------------


def test_fixture_decodes_with_its_prior_to_its_expected_grid():
    prior = read_prior((PRIOR_FIXTURES / "prior-1.0.mzp").read_bytes())
    data = (PRIOR_FIXTURES / "residual-1.0.mzw2").read_bytes()
    expected = read_any((PRIOR_FIXTURES / "residual-1.0.mzw2.expected.zg").read_bytes(), "expected")
    assert_same_grid(mzc.decode(data, prior=prior), expected)
    assert data[17:49] == hashlib.sha256(prior.data).digest()
    assert 0 < np.isnan(expected.z).sum() < expected.z.size


def test_prior_fixtures_are_never_regenerated():
    lines = (PRIOR_FIXTURES / "SHA256SUMS").read_text().split("\n")
    recorded = dict(reversed(line.split()) for line in lines if line)
    assert set(recorded) == {p.name for p in PRIOR_FIXTURES.iterdir() if p.name not in ("README.md", "SHA256SUMS")}
    for name, digest in recorded.items():
        assert hashlib.sha256((PRIOR_FIXTURES / name).read_bytes()).hexdigest() == digest, name


def spec_example():
    """(prior bytes, residual file bytes, expected values) of spec/prior.md's worked example."""
    text = SPEC.read_text()
    prior = re.search(r"```mzc-prior-example\n(.*?)```", text, re.S)[1].encode()
    magic, rest = re.search(r"```mzc-residual-example-hex\n(.*?)```", text, re.S)[1].split("\n", 1)
    expected = re.search(r"```mzc-residual-example-hex\n.*?```.*?```expected\n(.*?)```", text, re.S)[1]
    values = np.array([[float(v) for v in line.split()] for line in expected.strip().splitlines()])
    return prior, (magic + "\n").encode() + bytes.fromhex(rest), values


def test_spec_worked_example_decodes_to_what_the_page_says():
    prior, data, expected = spec_example()
    assert hashlib.sha256(prior).hexdigest() in SPEC.read_text()
    decoded = mzc.decode(data, prior=prior).z
    np.testing.assert_array_equal(np.isnan(decoded), np.isnan(expected))
    np.testing.assert_allclose(decoded[~np.isnan(decoded)], expected[~np.isnan(expected)], atol=1e-9)
    inner = mzc.decode(data[len(RESIDUAL_MAGIC) + 32:])   # the inner file is a dwt2d file of its own
    assert inner.z[0, 0] == pytest.approx(0.06)


# --- training, slicing on the lattice, coding --------------------------------------------


def test_train_covers_every_surface_and_fills_every_node(trained):
    assert trained.surfaces == 4 and trained.mean.valid.all()
    assert trained.data.startswith(PRIOR_MAGIC) and read_prior(trained.data).name == trained.name
    shifted = bump(8, 0.1, shape=(24, 36))   # wider than the first: the lattice grows to cover it
    grown = mzc.train([bump(8, 0.1), shifted])
    assert grown.mean.shape[1] > mzc.slice(bump(8, 0.1)).shape[1]
    assert grown.mean.origin == mzc.slice(bump(8, 0.1)).origin


def test_a_prior_file_reads_as_its_mean_grid(trained, tmp_path):
    path = tmp_path / "p.mzp"
    path.write_bytes(trained.data)
    assert_same_grid(mzc.read(path), trained.mean)


@pytest.mark.parametrize("options", [{"max_error": 0.02}, {"rmse": 0.01}, {}])
def test_a_surface_on_the_lattice_round_trips_within_its_bound(trained, options):
    grid = mzc.slice(bump(8.2, 0.09, holes=True), prior=trained)
    assert grid.shape == trained.mean.shape and not grid.valid.all()
    data = mzc.encode(grid, prior=trained, **options)
    decoded = mzc.decode(data, prior=trained)
    np.testing.assert_array_equal(decoded.valid, grid.valid)
    error = np.abs(decoded.z - grid.z)[grid.valid]
    if "max_error" in options:
        assert error.max() <= options["max_error"]
    assert len(data) <= len(mzc.encode(grid, **options))   # never larger than the plain file


def test_the_residual_is_written_when_it_is_smaller_and_its_rmse_is_the_rebuilt_surfaces(trained):
    grid = mzc.slice(bump(8.2, 0.09), prior=trained)
    data = mzc.encode(grid, prior=trained, rmse=0.02)
    assert data.startswith(RESIDUAL_MAGIC)
    plain = mzc.decode(mzc.encode(grid, rmse=0.02)).z - grid.z
    rebuilt = mzc.decode(data, prior=trained).z - grid.z
    # the planar bump's lean is small: both node RMS errors are near the target, neither far below
    for error in (plain, rebuilt):
        assert 0.4 * 0.02 < np.sqrt(np.mean(error[grid.valid] ** 2)) < 1.5 * 0.02


def test_the_rmse_weights_come_from_the_surface_not_the_residual():
    """On a central grid the residual's values are no distances from the centre: the rate control
    measures the rebuilt surface (dwt2d's ``surface``), so the error it reaches is the target's."""
    from mzc.codecs.dwt2d import encode_whole

    grid = mzc.slice(mzc.sample("blob"), charts=1)
    residual = grid.with_z(np.where(grid.valid, grid.z - np.nanmean(grid.z), np.nan))
    as_surface = encode_whole(residual, rmse=0.05, slope_limit=1.0, surface=grid)[0]
    as_values = encode_whole(residual, rmse=0.05, slope_limit=1.0)[0]
    assert as_surface != as_values


@settings(max_examples=25, deadline=None)
@given(st.integers(4, 12), st.integers(4, 12), st.integers(0, 2**32 - 1), st.sampled_from([0.01, 0.1, 1.0]))
def test_random_grids_round_trip_within_max_error(rows, cols, seed, bound):
    rng = np.random.default_rng(seed)
    mean = mzc.ZGrid(rng.normal(0, 10, (rows, cols)), 0.5, 0.5)
    prior = prior_of(mean, 3)
    z = mean.z + rng.normal(0, 1, (rows, cols))
    z[rng.random((rows, cols)) < 0.2] = np.nan
    z[0, 0] = 1.0
    grid = mzc.ZGrid(z, 0.5, 0.5)
    for data in (mzc.encode(grid, prior=prior, max_error=bound),
                 residual_file(grid, prior, mzc.get_codec("dwt2d").checked({"max_error": bound}))):
        decoded = mzc.decode(data, prior=prior.data)
        np.testing.assert_array_equal(decoded.valid, grid.valid)
        assert np.abs(decoded.z - grid.z)[grid.valid].max() <= bound


# --- refusals: one line each ---------------------------------------------------------------


def test_decoding_needs_the_very_prior(trained):
    grid = mzc.slice(bump(8.2, 0.09), prior=trained)
    data = residual_file(grid, trained, {"rmse": 0.02})
    with pytest.raises(MzcError, match=f"prior {trained.name}: give that prior file with --prior"):
        mzc.decode(data)
    other = mzc.train([bump(8, 0.1), bump(9, 0.05)])
    with pytest.raises(MzcError, match=f"prior {trained.name}, not the one given \\({other.name}\\)"):
        mzc.decode(data, prior=other)


def test_a_grid_off_the_lattice_is_refused_naming_the_field_and_the_fix(trained):
    grid = mzc.slice(bump(8.2, 0.09), d1=0.5)
    with pytest.raises(MzcError, match="the grid's d1 differs from the prior's .*mzc slice --prior"):
        mzc.encode(grid, prior=trained)
    with pytest.raises(MzcError, match="codes with dwt2d"):
        mzc.encode(mzc.slice(bump(8.2, 0.09), prior=trained), "dct", prior=trained, quality=20)
    with pytest.raises(MzcError, match="does not apply beside it") as error:
        mzc.slice(bump(8.2, 0.09), d1=0.5, prior=trained)
    assert error.value.field == "d1"


@pytest.mark.parametrize("damage, message", [
    (lambda d: d.replace(b"mzc-prior 1.0", b"mzc-prior 2.0", 1), "not a prior file"),
    (lambda d: d.replace(b"surfaces 4", b"surfaces 04", 1), "surfaces N"),
    (lambda d: d[:200], "."),
    (lambda d: b"", "not a prior file"),
])
def test_a_damaged_prior_is_refused(trained, damage, message):
    with pytest.raises(MzcError, match=message):
        read_prior(damage(trained.data))


def test_a_prior_with_a_hole_is_refused():
    mean = mzc.ZGrid(np.array([[1.0, np.nan], [2.0, 3.0]]), 1.0, 1.0)
    with pytest.raises(MzcError, match="a value at every node"):
        read_prior(PRIOR_MAGIC + b"surfaces 1\n" + zgrid.write(mean))


def test_a_cut_residual_file_is_refused(trained):
    data = residual_file(mzc.slice(bump(8.2, 0.09), prior=trained), trained, {"rmse": 0.02})
    for cut in (data[:20], data[:60], data[:-3]):
        with pytest.raises(MzcError):
            mzc.decode(cut, prior=trained)


# --- the command line ----------------------------------------------------------------------


def test_the_commands_train_slice_encode_decode_and_info(tmp_path):
    meshes = []
    for index, (amplitude, tilt) in enumerate([(8, 0.1), (9, 0.05), (7, 0.15)]):
        meshes.append(tmp_path / f"s{index}.ply")
        mzc.write(meshes[-1], bump(amplitude, tilt))
    target = tmp_path / "t.ply"
    mzc.write(target, bump(8.2, 0.09, holes=True))
    prior, grid, coded, back = (tmp_path / name for name in ("p.mzp", "t.zg", "t.mzw2", "back.zg"))
    run_mzc("train", *meshes, "-o", prior, check=True)
    run_mzc("slice", "--prior", prior, target, "-o", grid, check=True)
    run_mzc("encode", "--prior", prior, "--max-error", "0.02", grid, "-o", coded, check=True)
    assert coded.read_bytes().startswith(RESIDUAL_MAGIC)
    digest = hashlib.sha256(prior.read_bytes()).hexdigest()
    missing = run_mzc("decode", coded, "-o", back)
    assert missing.returncode == 1 and missing.stderr.decode().count("\n") == 1
    assert digest in missing.stderr.decode() and "--prior" in missing.stderr.decode()
    run_mzc("decode", "--prior", prior, coded, "-o", back, check=True)
    original, decoded = mzc.read(grid), mzc.read(back)
    assert np.abs(decoded.z - original.z)[original.valid].max() <= 0.02
    info = run_mzc("info", coded, check=True).stdout.decode()
    assert "mzc-residual 1.0" in info and digest in info
    assert digest in run_mzc("info", prior, check=True).stdout.decode()
    run_mzc("slice", "--d1", "0.5", target, "-o", tmp_path / "own.zg", check=True)   # not the prior's lattice
    refusals = {("slice", "--prior", prior, "--d1", "0.5", target): "--d1: the prior's lattice",
                ("encode", "--prior", prior, tmp_path / "own.zg"): "differs from the prior's"}
    for refused, message in refusals.items():
        result = run_mzc(*refused)
        assert result.returncode != 0 and result.stderr.decode().count("\n") == 1 and message in result.stderr.decode()


# --- the real faces, leave-one-out ---------------------------------------------------------


@pytest.mark.skipif(len(FACE_NAMES) < 5, reason="shared face data not available")
def test_a_face_coded_against_the_others_prior_is_smaller_at_a_coarse_target():
    held, others = face_path("f36.ply"), [face_path(name) for name in FACE_NAMES if name != "f36.ply"][:6]
    prior = mzc.train(others)
    grid = mzc.slice(held, prior=prior)
    data = mzc.encode(grid, prior=prior, rmse=0.2)
    assert data.startswith(RESIDUAL_MAGIC)
    assert len(data) < 0.9 * len(mzc.encode(mzc.slice(held), rmse=0.2))
    decoded = mzc.decode(data, prior=prior)
    np.testing.assert_array_equal(decoded.valid, grid.valid)
    assert decoded.projection == grid.projection == "spherical" and decoded.source_vertices == grid.source_vertices
    inner = mzc.decode(data[len(RESIDUAL_MAGIC) + 32:])   # the residual alone: planar, the lattice is the prior's
    assert inner.projection == "planar" and inner.shape == grid.shape
    bounded = mzc.decode(mzc.encode(grid, prior=prior, max_error=0.05), prior=prior)
    assert np.abs(bounded.z - grid.z)[grid.valid].max() <= 0.05


# --- mzc batch --prior ---------------------------------------------------------------------


def test_a_batch_item_is_cut_and_coded_against_the_prior_and_decoded_with_it(tmp_path, trained):
    from mzc.batch import Job, items, work

    path, mesh = tmp_path / "p.mzp", tmp_path / "t.ply"
    path.write_bytes(trained.data)
    mzc.write(mesh, bump(8.2, 0.09))
    named = {"path": str(path), "sha256": trained.name}
    encoding = {"codec": "dwt2d", "codec_options": {"rmse": 0.02}, "slice_options": {}, "prior": named}
    row = work.run_item(Job("encode", str(tmp_path / "out"), encoding), items.Item(str(mesh), "t.mzw2"))
    data = (tmp_path / "out" / "t.mzw2").read_bytes()
    assert row["status"] == "ok" and data.startswith(RESIDUAL_MAGIC)
    assert data == mzc.encode(mzc.slice(mesh, prior=trained), prior=trained, rmse=0.02)   # as slice | encode
    decoding = {"densify": 0, "method": "biharmonic", "format": "ply", "jump_angle": None}
    coded = items.Item(str(tmp_path / "out" / "t.mzw2"), "t.ply")
    row = work.run_item(Job("decode", str(tmp_path / "meshes"), {**decoding, "prior": named}), coded)
    assert row["status"] == "ok" and row["valid_nodes"] == mzc.decode(data, prior=trained).valid.sum()
    row = work.run_item(Job("decode", str(tmp_path / "alone"), decoding), coded)
    assert row["status"] == "failed" and trained.name in row["error"] and "\n" not in row["error"]
    with pytest.raises(MzcError, match="codes with dwt2d"):
        mzc.batch_encode(str(mesh), tmp_path / "dct", "dct", prior=path, quality=20)


def test_a_batch_refuses_an_option_that_shapes_a_grid_beside_a_prior_before_any_work(tmp_path, trained):
    """The lattice is the prior's: --d1 beside --prior is refused once, naming it, not on every item."""
    path, mesh = tmp_path / "p.mzp", tmp_path / "t.ply"
    path.write_bytes(trained.data)
    mzc.write(mesh, bump(8.2, 0.09))
    with pytest.raises(MzcError, match="does not apply beside it") as error:
        mzc.batch_encode(str(mesh), tmp_path / "out", slice_options={"d1": 0.5}, prior=path, rmse=0.02)
    assert error.value.field == "d1" and not (tmp_path / "out").exists()
    result = run_mzc("batch", "encode", str(mesh), "-o", str(tmp_path / "cli"), "--d1", "0.5", "--prior", str(path),
                     "--dwt2d")
    assert result.returncode != 0 and result.stderr.count(b"\n") == 1 and b"beside it" in result.stderr
    assert not (tmp_path / "cli").exists()


# --- hostile bytes ---------------------------------------------------------------------------

FIXTURE_PRIOR = (PRIOR_FIXTURES / "prior-1.0.mzp").read_bytes()
FIXTURE_RESIDUAL = (PRIOR_FIXTURES / "residual-1.0.mzw2").read_bytes()


@settings(max_examples=80, deadline=None)
@given(st.binary(max_size=400), st.sampled_from(["prior", "prior with its count", "residual"]))
def test_garbage_after_a_magic_line_is_refused_in_one_mzc_error(tail, kind):
    prior = read_prior(FIXTURE_PRIOR)
    head = {"prior": PRIOR_MAGIC, "prior with its count": PRIOR_MAGIC + b"surfaces 3\n",
            "residual": RESIDUAL_MAGIC + prior.digest}[kind]
    with pytest.raises(MzcError) as error:
        read_prior(head + tail) if kind.startswith("prior") else mzc.decode(head + tail, prior=prior)
    assert "\n" not in str(error.value)


@settings(max_examples=80, deadline=None)
@given(st.integers(0, len(FIXTURE_RESIDUAL) - 1), st.integers(1, 255))
def test_a_damaged_residual_file_is_refused_or_decodes_on_the_lattice(position, flip):
    prior = read_prior(FIXTURE_PRIOR)
    damaged = bytearray(FIXTURE_RESIDUAL)
    damaged[position] ^= flip
    try:
        grid = mzc.decode(bytes(damaged), prior=prior)
    except MzcError:
        return
    assert grid.shape == prior.mean.shape and grid.projection == prior.mean.projection
