"""The format promise: a file that a released mzc wrote decodes the same way for good.

tests/fixtures/ holds one small file of every format version, each beside the grid it
decodes to (``NAME.expected.zg``, written exactly). Every fixture must decode to its
expectation (to one part in 10^12), every readable (kind, major) must have a fixture, and the
fixtures themselves are never regenerated (tests/fixtures/README.md, SHA256SUMS). Also the
version rule for projections: central grids take the next major version, which older
majors refuse, and the readers' checks of projection, radius, poles and full turns.
"""

import hashlib

import numpy as np
import pytest

from mzc.codecs import BUILT_IN, dwt2d, get_codec
from mzc.codecs.dwt2d import compact
from mzc.codecs.rows import dct, dft, dwt, poly
from mzc.errors import MzcError, MzcWarning
from mzc.formats import module_for, read_any, zgrid
from mzc.formats.header import split_magic
from mzc.grid import IDENTITY_TRANSFORM, ZGrid

from codec_contract import (
    EXPECTED,
    FIXTURE_NAME,
    FIXTURES,
    assert_same_grid,
    expected_grid,
    fixture_bytes,
    fixture_names,
    rechecksummed,
)

REGISTRY = ("zgrid", *BUILT_IN)   # mzc's own formats, each with its fixtures
EXTENSIONS = {"zgrid": ".zg", **{name: get_codec(name).extension for name in BUILT_IN}}
ROW_CODECS = ("poly", "dft", "dct", "dwt")
NAME = FIXTURE_NAME


# --- the fixtures decode as they always did ---------------------------------------------


@pytest.mark.parametrize("name", fixture_names())
def test_fixture_decodes_to_its_expected_grid(name):
    """Each fixture decodes to its expected grid; a cut progressive file says so in its one warning."""
    if name.endswith("-cut.mzw2"):
        with pytest.warns(MzcWarning, match="cut short"):
            decoded = read_any(fixture_bytes(name), name)
    else:
        decoded = read_any(fixture_bytes(name), name)
    assert_same_grid(decoded, expected_grid(name))


@pytest.mark.parametrize("name", fixture_names())
def test_fixture_name_states_its_magic_line_and_extension(name):
    parts = NAME.match(name)
    kind, major, minor = split_magic(fixture_bytes(name), name)
    assert (kind, major, minor) == (parts["kind"], int(parts["major"]), int(parts["minor"]))
    assert parts["ext"] == EXTENSIONS[kind]


def written_versions(module):
    """The versions a format's writer writes: planar and projected grids, the z-grid's raw
    body (RAW_VERSION), a third version above both, the georeferenced planar grids of rasters
    (GEOREF_SINCE: a minor version of a major), multi-chart grids (CHARTED_VERSION), grids with
    colours (COLOURED_VERSION) or colours finer than the nodes (FINE_COLOURED_VERSION),
    tiled rasters of integers (ROUNDED_TILED_VERSION), tiled grids with colours
    (COLOURED_TILED_VERSION), grids that
    record their source's vertex count (COUNTED_SINCE: a minor version of a major) and grids coded
    with models per detail band (BAND_MODELS_VERSION)."""
    return {module.VERSION, module.PROJECTED_VERSION, getattr(module, "RAW_VERSION", module.VERSION),
            *module.GEOREF_SINCE.items(), *getattr(module, "COUNTED_SINCE", {}).items(),
            getattr(module, "CHARTED_VERSION", module.VERSION),
            getattr(module, "COLOURED_VERSION", module.VERSION),
            getattr(module, "FINE_COLOURED_VERSION", module.VERSION),
            getattr(module, "ROUNDED_TILED_VERSION", module.VERSION),
            getattr(module, "COLOURED_TILED_VERSION", module.VERSION),
            getattr(module, "BAND_MODELS_VERSION", module.VERSION)}


def newest_major(kind):
    """The newest major version ``kind``'s reader reads, the newest one its writer writes."""
    return max(written_versions(module_for(kind)))[0]


def readable_versions():
    """Every (kind, major, minor) the registry reads: each format's OLDEST_MAJOR up to its newest
    (newest_major), and within each major every minor up to the one its writer writes (minor 0
    alone for a major no longer written)."""
    versions = set()
    for kind in REGISTRY:
        written = written_versions(module_for(kind))
        for major in range(module_for(kind).OLDEST_MAJOR, newest_major(kind) + 1):
            newest = max((minor for m, minor in written if m == major), default=0)
            versions |= {(kind, major, minor) for minor in range(newest + 1)}
    return versions


def test_every_readable_version_has_exactly_one_fixture():
    """One fixture a version, not counting its variants (``NAME-VARIANT.EXT``: a 7.0 file with colours)."""
    found = [split_magic(fixture_bytes(name), name) for name in fixture_names() if not NAME.match(name)["variant"]]
    assert len(found) == len(set(found)), "two fixtures of one version"
    missing, extra = readable_versions() - set(found), set(found) - readable_versions()
    assert not missing, f"readable versions without a fixture: {sorted(missing)}"
    assert not extra, f"fixtures of versions the registry does not read: {sorted(extra)}"
    assert set(REGISTRY) == set(EXTENSIONS), "a new format needs its extension here and its fixtures"


def test_every_fixture_has_its_expectation_and_nothing_is_left_over():
    names = set(fixture_names())
    for path in FIXTURES.iterdir():
        if path.name.endswith(EXPECTED):
            assert path.name[:-len(EXPECTED)] in names, f"{path.name} expects a fixture that is not there"
    for name in names:
        assert (FIXTURES / (name + EXPECTED)).is_file(), f"{name} has no {name}{EXPECTED}"


def newest_fixtures():
    """The fixtures of each kind's newest readable major (newest_major)."""
    return [n for n in fixture_names() if split_magic(fixture_bytes(n), n)[1] == newest_major(n.split("-")[0])]


@pytest.mark.parametrize("name", newest_fixtures())
def test_the_major_above_the_newest_fixture_is_refused(name):
    """No readable major lies above the fixtures: the coverage above is not short of one."""
    kind, major, minor = split_magic(fixture_bytes(name), name)
    newer = fixture_bytes(name).replace(f"mzc-{kind} {major}.{minor}\n".encode(),
                                        f"mzc-{kind} {major + 1}.0\n".encode(), 1)
    with pytest.raises(MzcError, match="newer than this mzc reads") as error:
        read_any(newer, name)
    assert error.value.line == 1


def test_fixtures_are_never_regenerated():
    """SHA256SUMS (``sha256sum -c`` in tests/fixtures) pins every fixture and expectation byte."""
    recorded = {}
    for line in (FIXTURES / "SHA256SUMS").read_text().splitlines():
        digest, name = line.split()
        recorded[name] = digest
    on_disk = {p.name for p in FIXTURES.iterdir() if NAME.match(p.name.removesuffix(EXPECTED))}
    assert set(recorded) == on_disk, "a fixture added or removed without its line in SHA256SUMS"
    for name, digest in recorded.items():
        assert hashlib.sha256((FIXTURES / name).read_bytes()).hexdigest() == digest, (
            f"{name} changed: fixtures are written once; a decoding change is a new format version")


# --- the fixtures cover what they are there for ------------------------------------------


def grids():
    return {name: expected_grid(name) for name in fixture_names()}


def test_fixtures_span_planar_spherical_cylindrical_full_turn_holes_and_transforms():
    for name, grid in grids().items():
        kind, major, minor = split_magic(fixture_bytes(name), name)
        georeferenced = minor >= module_for(kind).GEOREF_SINCE.get(major, minor + 1)
        newest = major == module_for(kind).PROJECTED_VERSION[0]   # holds a projected grid, the older ones planar
        assert (grid.projection != "planar") == (newest and not georeferenced), name
        assert grid.georeferenced == georeferenced, name   # a raster's planar grid, with its CRS and layout
        assert 0 < np.isnan(grid.z).sum() < grid.z.size, name
    projections = {(split_magic(fixture_bytes(n), n)[0], g.projection, g.periodic) for n, g in grids().items()}
    for kind in REGISTRY:
        assert (kind, "planar", False) in projections
    assert {p for _, p, _ in projections} == {"planar", "spherical", "cylindrical"}
    assert any(p == "cylindrical" and periodic for _, p, periodic in projections), "no full-turn fixture"
    assert any(not np.array_equal(g.transform, IDENTITY_TRANSFORM) for g in grids().values())
    assert any(g.nodata != "nan" for g in grids().values())


def has_interior_hole(row):
    valid = np.flatnonzero(~np.isnan(row))
    return valid.size > 0 and np.isnan(row[valid[0]:valid[-1]]).any()


@pytest.mark.parametrize("name", [n for n in fixture_names() if n.split("-")[0] in ROW_CODECS])
def test_row_codec_fixtures_carry_a_holes_section(name):
    assert any(line.startswith("holes ") for line in fixture_bytes(name).decode().splitlines())
    assert any(has_interior_hole(row) for row in expected_grid(name).z)


def test_the_projected_dwt2d_fixture_decodes_through_its_projection():
    """dwt2d 3.0 steps depend on the projection's metric: read as planar, the same payload
    decodes to other heights, so the 3.0 fixture pins the projected decoding path."""
    name = "dwt2d-3.0.mzw2"
    data = fixture_bytes(name)
    header, payload = data.split(b"\ndata\n", 1)
    planar_header = [line for line in header.split(b"\n")
                     if not line.startswith((b"projection ", b"radius "))]
    as_planar = read_any(b"\n".join(planar_header) + b"\ndata\n" + payload, name)
    projected = read_any(data, name)
    assert projected.projection == "cylindrical" and projected.periodic
    assert np.array_equal(np.isnan(as_planar.z), np.isnan(projected.z))
    assert np.nanmax(np.abs(as_planar.z - projected.z)) > 0.05


# --- the version rule for projections: refusals -------------------------------------------


def zgrid_text(magic="mzc-zgrid 1.0", extra="", rows=2, cols=3, d1="1", d2="1", origin="0 0"):
    lines = [magic, f"rows {rows}", f"cols {cols}", f"d1 {d1}", f"d2 {d2}", f"origin {origin}"]
    lines += [line for line in extra.split("\n") if line]
    lines += ["data"] + [" ".join(["50"] * cols)] * rows
    return ("\n".join(lines) + "\n").encode()


def refusal(data, source="hand.zg"):
    with pytest.raises(MzcError) as error:
        read_any(data, source)
    return error.value


def test_a_projection_line_in_an_old_major_zgrid_is_refused():
    error = refusal(zgrid_text(extra="projection spherical\nradius 100"))
    assert (error.field, error.line) == ("projection", 7)
    assert "spherical" in error.message and "newer major version" in error.message
    assert str(error).startswith("hand.zg:7: projection: ")


@pytest.mark.parametrize("name", [n for n in fixture_names()
                                  if split_magic(fixture_bytes(n), n)[1]
                                  < module_for(n.split("-")[0]).PROJECTED_VERSION[0]])
def test_every_planar_major_refuses_a_projection_line(name):
    """Inserted into each real planar fixture (text header, even before dwt2d's binary payload)."""
    first, rest = fixture_bytes(name).split(b"\n", 1)
    error = refusal(rechecksummed(first + b"\nprojection cylindrical\nradius 40\n" + rest), name)
    assert (error.field, error.line) == ("projection", 2)
    assert "newer major version" in error.message


@pytest.mark.parametrize("magic", ["mzc-zgrid 1.0", "mzc-zgrid 2.0"])
def test_a_radius_on_a_planar_grid_is_refused(magic):
    error = refusal(zgrid_text(magic=magic, extra="radius 100"))
    assert (error.field, error.line) == ("radius", 7)
    assert "central projection" in error.message


def test_a_central_grid_needs_a_radius():
    error = refusal(zgrid_text(magic="mzc-zgrid 2.0", extra="projection cylindrical"))
    assert error.field == "radius" and "missing" in error.message


@pytest.mark.parametrize("origin", ["0 100", "0 -200"])
def test_a_spherical_grid_whose_rows_pass_a_pole_is_refused(origin):
    # radius 100: the poles are at v = +-50 pi = +-157.08; rows 0 and 1 sit at v0 and v0 + 80
    error = refusal(zgrid_text(magic="mzc-zgrid 2.0", extra="projection spherical\nradius 100",
                               d1="80", origin=origin))
    assert error.field == "d1" and "poles" in error.message


def test_a_spherical_grid_from_pole_to_pole_is_read():
    radius, rows = 100.0, 5
    grid = ZGrid(np.full((rows, 4), 100.0), d1=np.pi * radius / (rows - 1), d2=10,
                 origin=(0, -np.pi / 2 * radius), projection="spherical", radius=radius)
    back = read_any(zgrid.write(grid), "poles.zg")
    assert back.pole_rows().tolist() == [True, False, False, False, True]


def test_a_central_grid_spanning_more_than_a_turn_is_refused():
    # radius 1: a turn is 2 pi = 6.283; 7 columns of 1 span 7
    error = refusal(zgrid_text(magic="mzc-zgrid 2.0", extra="projection cylindrical\nradius 1", cols=7))
    assert error.field == "d2" and "more than a full turn" in error.message
    # as mzc slices a full turn (d2 = 2 pi R0 / cols) it is read, and its columns wrap
    turn = read_any(zgrid_text(magic="mzc-zgrid 2.0", extra="projection cylindrical\nradius 1", cols=7,
                               d2=repr(2 * np.pi / 7)), "turn.zg")
    assert turn.periodic


@pytest.mark.parametrize("kind", sorted(REGISTRY))
def test_a_newer_major_is_refused_with_an_upgrade_hint(kind):
    major = newest_major(kind) + 1
    error = refusal(f"mzc-{kind} {major}.0\nrows 1\ncols 1\nd1 1\nd2 1\ndata\n".encode())
    assert error.line == 1 and f"mzc-{kind} version {major}.x is newer" in error.message
    assert "upgrade mzc" in error.message


def test_zgrid_7_is_refused_as_newer():
    error = refusal(zgrid_text(magic="mzc-zgrid 7.0"))
    assert error.line == 1 and "newer than this mzc reads (6.x)" in error.message


# --- the version rule for projections: what writers write ---------------------------------

WRITERS = {
    "zgrid": (zgrid.write, {}),
    "poly": (poly.write, {"degree": 3}),
    "dft": (dft.write, {"quality": 50}),
    "dct": (dct.write, {"quality": 50}),
    "dwt": (dwt.write, {"quality": 50}),
    "dwt2d": (dwt2d.write, {"max_error": 0.05}),
}


@pytest.mark.parametrize("kind", sorted(WRITERS))
@pytest.mark.parametrize("source, projected", [("zgrid-1.0.zg", False), ("zgrid-2.0.zg", True),
                                               ("dct-2.0.mzd", True)])
def test_writers_take_the_projected_version_for_central_grids_only(kind, source, projected):
    write, options = WRITERS[kind]
    grid = expected_grid(source)
    module = module_for(kind)
    major, minor = module.PROJECTED_VERSION if projected else module.VERSION
    data = write(grid, **options)
    if kind == "dwt2d":   # 10.0 for every grid coded whole (its 3.x is what a 5.0 file's tiles are)
        assert data.startswith(b"mzc-dwt2d 10.0\n")
        assert compact.read(data, kind)[0].has("projection") == projected
        data = dwt2d.encode_whole(grid, **options, compact=False)[0]
    assert data.startswith(f"mzc-{kind} {major}.{minor}\n".encode())
    assert (b"\nprojection " in data.split(b"\ndata\n")[0]) == projected
    assert read_any(data, kind).projection == grid.projection


@pytest.mark.parametrize("name", ["zgrid-1.0.zg", "zgrid-2.0.zg"])
def test_the_zgrid_writer_writes_its_fixtures_again_byte_for_byte(name):
    assert zgrid.write(read_any(fixture_bytes(name), name)) == fixture_bytes(name)
