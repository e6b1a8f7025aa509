"""The colour section (mzc.codecs.dwt2d.colour, spec/colour.md): round trips within the bound
asked, lossless at max_error 0, PSNR targets met on real and generated images, damaged bytes
refused with one-line MzcErrors, the spec's worked example and the fixture decoded, the same
bytes with numpy's SIMD loops switched off."""

import functools
import hashlib
import json
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mzc.codecs.dwt2d import colour
from mzc.errors import MzcError

from conftest import REPO

sys.path.insert(0, str(REPO / "benchmarks"))

import colour as benchmark  # noqa: E402

FIXTURES = REPO / "tests" / "fixtures" / "colour"
FIXTURE_NAMES = {"colour-section-1": 1, "colour-section-1-integer": 0, "colour-section-2": 1,
                 "colour-section-3": 1}   # name: its transform
SPEC = REPO / "spec" / "colour.md"


def texture(size=128):
    """A crop of the fuze's real JPEG texture (skipped when absent)."""
    if not (benchmark.FUZE / "fuze uv.jpg").is_file():
        pytest.skip("tests/data/public/fuze is absent")
    image, _mask = benchmark.fuze_texture(quick=False)
    return np.ascontiguousarray(image[300:300 + size, 200:200 + size])


def milk():
    """PCL's milk carton, gridded (skipped when absent)."""
    if not benchmark.MILK.is_file():
        pytest.skip("tests/data/public/pcl-milk is absent")
    points, colours = benchmark.milk_cloud()
    rgb, mask, _nodes = benchmark.gridded(points, colours, len(points))
    return rgb, mask


def psnr(decoded, rgb, mask):
    return benchmark.colour_error(decoded, rgb, mask)["psnr"]


@st.composite
def images(draw):
    """Small images with masks: noise, flat colours or smooth ramps, any mask (even none valid)."""
    rows, cols = draw(st.integers(1, 20)), draw(st.integers(1, 20))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    kind = draw(st.sampled_from(["noise", "flat", "ramp"]))
    if kind == "noise":
        rgb = rng.integers(0, 256, (rows, cols, 3))
    elif kind == "flat":
        rgb = np.broadcast_to(rng.integers(0, 256, 3), (rows, cols, 3))
    else:
        r, c = np.mgrid[0:rows, 0:cols]
        rgb = np.stack([r * 13 % 256, c * 7 % 256, (r + c) * 5 % 256], axis=-1)
    mask = rng.random((rows, cols)) < draw(st.sampled_from([0.0, 0.5, 0.9, 1.0]))
    return rgb.astype(np.uint8), mask


@settings(max_examples=150, deadline=None)
@given(images(), st.integers(0, 40), st.one_of(st.none(), st.integers(0, 4)))
def test_max_error_holds_at_every_valid_node_and_invalid_nodes_decode_to_0(image, max_error, levels):
    rgb, mask = image
    decoded = colour.decode_colour(colour.encode_colour(rgb, mask, max_error=max_error, levels=levels), mask)
    assert decoded.dtype == np.uint8 and decoded.shape == rgb.shape
    assert np.abs(decoded.astype(int) - rgb)[mask].max(initial=0) <= max_error
    assert not decoded[~mask].any()


@settings(max_examples=60, deadline=None)
@given(images(), st.integers(0, 5))
def test_max_error_0_is_lossless_by_the_integer_lifting_alone(image, levels):
    rgb, mask = image
    section = colour.encode_colour(rgb, mask, max_error=0, levels=levels)
    assert np.array_equal(colour.decode_colour(section, mask)[mask], rgb[mask])
    assert colour.read_header(section, "x")[5:10] == (0, 16, 16, 16, 0)   # the 5/3 at step 1, no correction


@settings(max_examples=100, deadline=None)
@given(st.integers(1, 40), st.integers(1, 6), st.integers(0, 2 ** 32 - 1))
def test_the_integer_lifting_and_colour_transform_invert_exactly(n, width, seed):
    rng = np.random.default_rng(seed)
    x = rng.integers(-600, 600, (n, width))
    assert np.array_equal(colour.merge_integer(*colour.split_integer(x)), x)
    plane = rng.integers(-600, 600, (n, n + width))
    assert np.array_equal(colour.inverse(colour.forward(plane, 3)), plane)
    rgb = rng.integers(0, 256, (n, width, 3)).astype(np.uint8)
    y, co, cg = colour.ycocg(rgb)
    assert y.min() >= 0 and y.max() <= 255 and np.abs(co).max() <= 255 and np.abs(cg).max() <= 255
    assert np.array_equal(colour.rgb_of(y, co, cg), rgb)


def test_every_colour_survives_ycocg_r():
    r, g, b = np.meshgrid(np.arange(256), np.arange(256), np.arange(0, 256, 5), indexing="ij")
    rgb = np.stack([r, g, b], axis=-1).astype(np.uint8)
    assert np.array_equal(colour.rgb_of(*colour.ycocg(rgb)), rgb)


@pytest.mark.parametrize("max_error", [0, 2, 6])
def test_real_texture_and_rgbd_cloud_within_max_error(max_error):
    rgb = texture()
    mask = np.ones(rgb.shape[:2], dtype=bool)
    mask[40:70, 10:50] = False
    for image, valid in ((rgb, mask), milk()):
        data = colour.encode_colour(image, valid, max_error=max_error)
        decoded = colour.decode_colour(data, valid)
        assert np.abs(decoded.astype(int) - image)[valid].max() <= max_error
        if max_error == 0:
            assert len(data) < image[valid].size   # below 8 bits a channel on a real image


@pytest.mark.parametrize("target", [28.0, 34.0, 40.0])
def test_a_psnr_target_is_met_within_a_tenth_of_a_db(target):
    for rgb, mask in ((texture(), np.ones((128, 128), dtype=bool)), benchmark.height_field_image(96, 80, seed=3)):
        data = colour.encode_colour(rgb, mask, psnr=target)
        reached = psnr(colour.decode_colour(data, mask), rgb, mask)
        assert target <= reached < target + 1.0
        assert len(data) < len(colour.encode_colour(rgb, mask, psnr=target + 3))


def test_chroma_is_quantised_coarser_than_luma():
    rgb, mask = benchmark.height_field_image(64, 64)
    fields = colour.read_header(colour.encode_colour(rgb, mask, psnr=32), "x")
    luma, co, cg = fields[6:9]
    assert co > luma and cg > luma


def test_the_colour_rms_goal_of_issue_32_is_met_far_below_draco_colour_bytes():
    """Colour RMS <= 12 levels (PSNR 26.5 dB) for a fraction of Draco's colour attribute."""
    rgb, mask = milk()
    data = colour.encode_colour(rgb, mask, psnr=30.0)
    error = benchmark.colour_error(colour.decode_colour(data, mask), rgb, mask)
    assert error["rms"] <= 12.0
    rows, cols = np.nonzero(mask)
    _with, _without, draco = benchmark.draco_colour_bytes(np.column_stack([cols, rows, 0 * rows]).astype(float),
                                                          rgb[rows, cols])
    assert len(data) < draco / 4


def test_bad_arguments_are_one_line_errors():
    rgb, mask = benchmark.height_field_image(16, 16)
    for call in (lambda: colour.encode_colour(rgb, mask, max_error=1, psnr=30),
                 lambda: colour.encode_colour(rgb, mask, max_error=1.5),
                 lambda: colour.encode_colour(rgb, mask, max_error=200),
                 lambda: colour.encode_colour(rgb, mask, psnr=-3),
                 lambda: colour.encode_colour(rgb.astype(np.int16), mask),
                 lambda: colour.encode_colour(rgb[:, :-1], mask),
                 lambda: colour.encode_colour(rgb, mask.astype(int))):
        with pytest.raises(MzcError) as error:
            call()
        assert "\n" not in str(error.value)


@functools.lru_cache(maxsize=1)
def small_section():
    """(a section of a small generated image at max_error 3, its mask): encoded once for the damage tests."""
    rgb, mask = benchmark.height_field_image(24, 20, seed=1)
    return colour.encode_colour(rgb, mask, max_error=3), mask


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_any_damaged_byte_is_refused(data):
    section, mask = small_section()
    position = data.draw(st.integers(0, len(section) - 1))
    damaged = bytearray(section)
    damaged[position] ^= data.draw(st.integers(1, 255))
    with pytest.raises(MzcError) as error:
        colour.decode_colour(bytes(damaged), mask, source="a.mzw2")
    assert str(error.value).startswith("a.mzw2: colour: ") and "\n" not in str(error.value)


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_truncated_or_extended_sections_and_other_masks_are_refused(data):
    section, mask = small_section()
    cut = data.draw(st.integers(0, len(section) - 1))
    for bad, bad_mask in ((section[:cut], mask), (section + b"\x00" * data.draw(st.integers(1, 9)), mask),
                          (section, mask[:, 1:])):
        with pytest.raises(MzcError):
            colour.decode_colour(bad, bad_mask)


def test_section_length_lets_a_container_append_more_sections():
    section, mask = small_section()
    assert colour.section_length(section + b"next section") == len(section)
    decoded = colour.decode_colour(section[:colour.section_length(section + b"tail")], mask)
    assert decoded.shape == mask.shape + (3,)


# --------------------------------------------------------------------------- fixture, spec, golden


def fixture(name):
    """(section bytes, node mask, charts, expected image) of a fixture of tests/fixtures/colour; the
    charts of a multi-chart grid's section (its ``views`` and ``blocks``), else None."""
    from mzc.grid import Chart

    expected = np.load(FIXTURES / f"{name}.expected.npz")
    charts = (tuple(Chart(str(view), *map(int, block)) for view, block in zip(expected["views"], expected["blocks"]))
              if "views" in expected else None)
    return (FIXTURES / f"{name}.bin").read_bytes(), expected["mask"], charts, expected["rgb"]


def test_the_fixtures_decode_to_their_expected_images_and_are_never_regenerated():
    for name, transform in FIXTURE_NAMES.items():
        section, mask, charts, rgb = fixture(name)
        assert colour.read_header(section, name)[5] == transform
        assert np.array_equal(colour.decode_colour(section, mask, charts=charts), rgb)
    assert fixture("colour-section-3")[2] is not None and len(list(FIXTURES.glob("*.bin"))) == len(FIXTURE_NAMES)
    for line in (FIXTURES / "SHA256SUMS").read_text().splitlines():
        digest, name = line.split()
        assert hashlib.sha256((FIXTURES / name).read_bytes()).hexdigest() == digest, name


def spec_example():
    """(the spec's worked example bytes, its mask, its decoded image) from spec/colour.md's code blocks."""
    text = SPEC.read_text()
    blocks = text.split("```")
    hex_block = next(b for b in blocks if b.startswith("hex\n"))
    mask_block = next(b for b in blocks if b.startswith("mask\n"))
    image_block = next(b for b in blocks if b.startswith("rgb\n"))
    section = bytes.fromhex("".join(hex_block.split()[1:]))
    mask = np.array([[c == "#" for c in row] for row in mask_block.split()[1:]])
    rgb = np.array([[int(v) for v in row.split()] for row in image_block.strip().splitlines()[1:]]).reshape(
        mask.shape + (3,))
    return section, mask, rgb


def test_the_spec_worked_example_decodes_to_the_image_it_shows():
    section, mask, rgb = spec_example()
    assert np.array_equal(colour.decode_colour(section, mask), rgb)


def decoded_digests():
    """{case: SHA-256 of the decoded image} of the fixture and of fresh sections of real images."""
    cases = {}
    for name in FIXTURE_NAMES:
        section, mask, charts, _rgb = fixture(name)
        cases[name] = colour.decode_colour(section, mask, charts=charts)
    rgb, mask = benchmark.height_field_image(64, 48, seed=5)
    cases["height field psnr 33"] = colour.decode_colour(colour.encode_colour(rgb, mask, psnr=33.0), mask)
    cases["height field section"] = np.frombuffer(colour.encode_colour(rgb, mask, max_error=2), dtype=np.uint8)
    return {case: hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest() for case, value in cases.items()}


def test_decode_gives_the_same_bytes_with_numpys_simd_loops_switched_off():
    """As tests/test_unchanged_outputs.py does for the golden outputs: a subprocess with numpy's
    AVX-512 and AVX2 loops switched off decodes (and encodes) the same bytes."""
    from test_unchanged_outputs import switched_off_environment

    environment, _off = switched_off_environment("AVX2 off")
    code = ("import json, sys; sys.path[:0] = [{tests!r}, {repo!r}]; import test_colour_codec as t; "
            "print(json.dumps(t.decoded_digests()))").format(tests=str(REPO / "tests"), repo=str(REPO))
    result = subprocess.run([sys.executable, "-c", code], env={**environment, "PYTHONPATH": str(REPO)},
                            capture_output=True, text=True, cwd=REPO)
    if "cannot disable" in result.stderr or "baseline" in result.stderr:
        pytest.skip(f"this numpy cannot switch off its AVX2 loops: {result.stderr.strip().splitlines()[-1]}")
    assert result.returncode == 0, result.stderr[-2000:]
    assert json.loads(result.stdout) == decoded_digests()



def test_the_benchmark_measures_every_contender_on_one_image():
    """benchmarks/colour.py on a small generated image: mzc meets its target, every peer is probed,
    Draco's colour bytes are positive, and the report names every image and peer."""
    rgb, mask = benchmark.height_field_image(48, 64, seed=2)
    item = benchmark.measure_image("small", rgb, mask, *benchmark.node_cloud(rgb, mask), "generated", (32.0,),
                                   lambda _text: None)
    assert item["mzc"][0]["colour"]["psnr"] >= 32.0 and item["mzc"][-1]["colour"]["rms"] == 0
    assert all(len(points) == len(benchmark.PEERS[peer][2]) for peer, points in item["peers"].items())
    assert item["draco"]["colour"] > 0 and item["draco"]["points"] == mask.sum()
    report = benchmark.markdown([item], {"quick": True, "commit": "x", "started": "now", "wall_s": 1.0}, (32.0,))
    assert "| small | 32 |" in report and all(peer in report for peer in benchmark.PEERS)
