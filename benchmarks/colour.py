"""mzc's colour section (mzc.codecs.dwt2d.colour) beside image codecs and Draco's colour attribute (issue 32).

    python benchmarks/colour.py [--quick] [--out DIR]

Every image is an (R, C, 3) uint8 grid of colours with a mask of valid nodes:

- ``fuze texture``: the JPEG texture of trimesh's fuze bottle (tests/data/public/fuze), every node valid.
- ``fuze surface (+z)``, ``milk carton (RGB-D)``: coloured points gridded HERE, by this script,
  until ``mzc slice`` samples colour (branch ``colour``): the points (the fuze surface sampled with
  the colour of its texture, PCL's Kinect cloud of a milk carton with its ``rgba``) are projected
  along z onto a regular grid of about one node per point, each node taking the colour of the
  nearest point, valid when one lies within a node spacing.
- ``height field``: a generated coloured terrain (hypsometric tints, hill shading, noise) under an
  elliptic mask with a hole.

Contenders, in the same run, at equal PSNR over the valid nodes (every error measured here,
from the decoded arrays): mzc ``encode_colour(psnr=P)``; JPEG XL, AVIF, WebP and JPEG 2000 through
imagecodecs on the image with invalid nodes filled by mzc's harmonic fill (the mask is the
container's in both cases, so neither pays for it), each probed on a ladder of its quality knob
and its bytes at the target interpolated log-log on its Pareto front (report.bytes_at); lossless
(mzc max_error 0, JPEG XL, WebP and JPEG 2000 lossless); and Draco's colour attribute at 8
bits: DracoPy's bytes of the valid nodes (or the gridded cloud's points) as a point cloud with
colours minus without, positions at 11 bits (Draco's colours are exact: RMS 0).
Writes colour-results.md and colour-results.json into --out (default: this directory).
"""

import datetime
import json
import time

from startup import HERE  # first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from report import benchmark_parser, bytes_at, fmt, git_commit, machine, pareto, terminal_progress, versions

from mzc.codecs.dwt2d import colour

PUBLIC = HERE.parent / "tests" / "data" / "public"
FUZE = PUBLIC / "fuze"
MILK = PUBLIC / "pcl-milk" / "milk_color.pcd"
PACKAGES = ("numpy", "constriction", "imagecodecs", "DracoPy", "trimesh", "scipy")
TARGETS = (30.0, 36.0, 42.0)      # PSNR, dB
QUICK_TARGETS = (36.0,)
POSITION_BITS = 11                # Draco's position quantisation
FUZE_SAMPLES = 60000
MZC = "mzc colour"
PEERS = {   # name: (encode(image, knob), decode, the knob's ladder from coarse to fine)
    "JPEG XL": (lambda im, k: __import__("imagecodecs").jpegxl_encode(im, distance=k, effort=7),
                lambda b: __import__("imagecodecs").jpegxl_decode(b),
                (25.0, 18.0, 12.0, 8.0, 5.0, 3.5, 2.5, 1.8, 1.3, 0.9, 0.6, 0.4, 0.25, 0.15, 0.08)),
    "AVIF": (lambda im, k: __import__("imagecodecs").avif_encode(im, level=k, speed=6),
             lambda b: __import__("imagecodecs").avif_decode(b), (0, 2, 5, 15, 25, 35, 45, 55, 65, 75, 85, 92, 97, 99)),
    "WebP": (lambda im, k: __import__("imagecodecs").webp_encode(im, level=k, lossless=False, method=6),
             lambda b: __import__("imagecodecs").webp_decode(b), (0, 2, 10, 20, 35, 50, 65, 80, 90, 95, 100)),
    "JPEG 2000": (lambda im, k: __import__("imagecodecs").jpeg2k_encode(im, level=k, codecformat="j2k"),
                  lambda b: __import__("imagecodecs").jpeg2k_decode(b), (18, 22, 26, 30, 34, 38, 42, 46, 50, 55)),
}
LOSSLESS = {
    "JPEG XL": lambda im: __import__("imagecodecs").jpegxl_encode(im, lossless=True, effort=7),
    "WebP": lambda im: __import__("imagecodecs").webp_encode(im, lossless=True, method=6),
    "JPEG 2000": lambda im: __import__("imagecodecs").jpeg2k_encode(im, level=0, codecformat="j2k",
                                                                    reversible=True),
}


# --------------------------------------------------------------------------- images


def height_field_image(rows=256, cols=256, seed=0):
    """(rgb, mask) of a generated coloured height field: a smooth random terrain tinted by height
    (green lowlands to brown to white peaks), hill-shaded from the north-west, with 3 levels of
    noise; valid inside an ellipse, less a round hole."""
    rng = np.random.default_rng(seed)
    r, c = np.mgrid[0:rows, 0:cols] / max(rows, cols)
    z = sum(rng.normal() / k * np.sin(2 * np.pi * k * (r * rng.normal() + c * rng.normal()) + rng.uniform(0, 6))
            for k in range(1, 9))
    z = (z - z.min()) / max(np.ptp(z), 1e-9)
    tints = np.array([[40, 110, 50], [120, 160, 70], [150, 110, 60], [110, 80, 60], [245, 245, 245]], dtype=float)
    position = z * (len(tints) - 1)
    low = np.minimum(position.astype(int), len(tints) - 2)
    weight = (position - low)[..., None]
    tint = tints[low] * (1 - weight) + tints[low + 1] * weight
    dy, dx = np.gradient(z * 40.0)
    shade = np.clip(0.75 + 0.25 * (-dx - dy) / np.sqrt(1 + dx ** 2 + dy ** 2), 0.3, 1.0)[..., None]
    rgb = np.clip(np.rint(tint * shade + rng.normal(0, 3, tint.shape)), 0, 255).astype(np.uint8)
    mask = ((r - 0.5 * rows / max(rows, cols)) / 0.48) ** 2 + ((c - 0.5 * cols / max(rows, cols)) / 0.45) ** 2 < 1
    mask &= (r - 0.3) ** 2 + (c - 0.6) ** 2 > 0.07 ** 2
    return np.where(mask[..., None], rgb, 0).astype(np.uint8), mask


def gridded(points, colours, nodes):
    """(rgb, mask, the valid nodes' positions) of coloured ``points`` projected along z onto a regular
    grid of about ``nodes`` nodes over their x, y extent: each node the colour of its nearest point,
    valid when that lies within one spacing (labelled 'gridded here': not mzc slice's sampling)."""
    from scipy.spatial import cKDTree

    low, high = points[:, :2].min(axis=0), points[:, :2].max(axis=0)
    spacing = float(np.sqrt(np.prod(high - low) / nodes))
    cols, rows = (np.floor((high - low) / spacing).astype(int) + 1)
    y, x = np.mgrid[0:rows, 0:cols] * spacing
    grid = np.column_stack([x.ravel() + low[0], y.ravel() + low[1]])
    distance, nearest = cKDTree(points[:, :2]).query(grid)
    mask = (distance <= spacing).reshape(rows, cols)
    rgb = np.where(mask[..., None], colours[nearest].reshape(rows, cols, 3), 0).astype(np.uint8)
    node_points = np.column_stack([grid, points[nearest, 2]]).reshape(rows, cols, 3)
    return rgb, mask, node_points[mask]


def fuze_texture(quick):
    """The fuze's texture image (halved in --quick), every node valid."""
    import imagecodecs

    image = imagecodecs.imread(FUZE / "fuze uv.jpg")[..., :3]
    image = image[::2, ::2].copy() if quick else image
    return image, np.ones(image.shape[:2], dtype=bool)


def fuze_surface():
    """Points sampled on the fuze bottle with their texture's colours (trimesh), seeded."""
    import trimesh

    mesh = trimesh.load(FUZE / "fuze.obj", force="mesh")
    points, _faces, colours = trimesh.sample.sample_surface(mesh, FUZE_SAMPLES, sample_color=True, seed=0)
    return np.asarray(points), np.asarray(colours)[:, :3].astype(np.uint8)


def milk_cloud():
    """PCL's milk carton: points and their colours (the ``rgba`` field's R, G, B)."""
    from mzc.meshes import pcd

    data = MILK.read_bytes()
    header = pcd.parse_header(data, MILK.name)
    columns = pcd.compressed_columns(header, data, ("x", "y", "z", "rgba"), MILK.name)
    points = np.column_stack([columns[name] for name in "xyz"])
    packed = columns["rgba"].astype(np.uint32)
    return points, np.column_stack([(packed >> 16) & 255, (packed >> 8) & 255, packed & 255]).astype(np.uint8)


def images(quick):
    """[(name, rgb, mask, points for Draco, their colours, what the image is)]."""
    found = []
    if FUZE.is_dir():
        texture, everywhere = fuze_texture(quick)
        found.append(("fuze texture", texture, everywhere, *node_cloud(texture, everywhere),
                      "trimesh's fuze.obj texture (JPEG), every node valid"))
        points, colours = fuze_surface()
        rgb, mask, _nodes = gridded(points, colours, 128 * 128)
        found.append(("fuze surface (+z)", rgb, mask, points, colours,
                      f"{FUZE_SAMPLES} textured surface samples, gridded here (nearest sample) along z"))
    if MILK.is_file():
        points, colours = milk_cloud()
        rgb, mask, _nodes = gridded(points, colours, len(points))
        found.append(("milk carton (RGB-D)", rgb, mask, points, colours,
                      f"PCL's {len(points)}-point Kinect cloud, gridded here (nearest point) along z"))
    rgb, mask = height_field_image()
    found.append(("height field", rgb, mask, *node_cloud(rgb, mask), "generated, 256 x 256, elliptic mask"))
    return found


def node_cloud(rgb, mask):
    """(points, colours) of an image's valid nodes as a point cloud (x = column, y = row, z = 0)."""
    rows, cols = np.nonzero(mask)
    return np.column_stack([cols, rows, np.zeros(len(rows))]).astype(np.float64), rgb[rows, cols]


# --------------------------------------------------------------------------- measures


def colour_error(decoded, rgb, mask):
    """{"rms": RMS in 8-bit levels, "psnr": dB, "max": largest |error|} over the valid nodes' channels."""
    error = (decoded.astype(np.float64) - rgb)[mask]
    mse = float(np.mean(error ** 2)) if error.size else 0.0
    return {"rms": float(np.sqrt(mse)), "psnr": float(10 * np.log10(255 ** 2 / mse)) if mse else float("inf"),
            "max": float(np.abs(error).max(initial=0))}


def filled_image(rgb, mask):
    """The image with invalid nodes given mzc's harmonic fill, channel by channel, as the peers see it."""
    return np.stack([colour.filled(rgb[..., i], mask) for i in range(3)], axis=-1).clip(0, 255).astype(np.uint8)


def mzc_points(rgb, mask, targets):
    """mzc's section at each PSNR target and losslessly: [{target, bytes, colour error, seconds}]."""
    points = []
    for target in [*targets, "lossless"]:
        start = time.perf_counter()
        data = colour.encode_colour(rgb, mask, **({"max_error": 0} if target == "lossless" else {"psnr": target}))
        encode_s = time.perf_counter() - start
        start = time.perf_counter()
        decoded = colour.decode_colour(data, mask)
        points.append({"target": target, "bytes": len(data), "colour": colour_error(decoded, rgb, mask),
                       "encode_s": encode_s, "decode_s": time.perf_counter() - start})
    return points


def peer_points(name, filled, rgb, mask):
    """A peer's probed points: [{knob, bytes, colour error}] over its ladder."""
    encode, decode, ladder = PEERS[name]
    points = []
    for knob in ladder:
        data = encode(filled, knob)
        points.append({"knob": knob, "bytes": len(data), "colour": colour_error(decode(data)[..., :3], rgb, mask)})
    return points


def at_psnr(points, psnr):
    """Bytes at the RMS of ``psnr`` interpolated log-log on the points' Pareto front; when even the
    coarsest setting probed is better than ``psnr``, its bytes (an upper bound); None when no setting
    reaches it. (An exact point, RMS 0, has no logarithm and is left out.)"""
    front = pareto([p for p in points if p["colour"]["rms"] > 0], "colour rms")
    return bytes_at(front, 255.0 / 10 ** (psnr / 20), below_cheapest=True)


def coarsest_psnr(points):
    """The PSNR of a peer's cheapest setting probed."""
    return min(points, key=lambda p: p["bytes"])["colour"]["psnr"]


def peer_cell(item, peer, target):
    """A peer's bytes at a PSNR target: '<=' its cheapest setting's when that is already better than the
    target, or the best PSNR its ladder reached when that is below the target."""
    found, points = item["at_psnr"][str(target)][peer], item["peers"][peer]
    if found is None:
        return f"n/a (reaches {max(p['colour']['psnr'] for p in points):.1f} dB)"
    return f"<= {found:.0f}" if coarsest_psnr(points) > target else f"{found:.0f}"


def lossless_bytes(filled):
    """{peer: bytes} of the lossless peers on the filled image."""
    return {name: len(encode(filled)) for name, encode in LOSSLESS.items()}


def draco_colour_bytes(points, colours):
    """(Draco's bytes with colours, without, the difference): a point cloud, positions at POSITION_BITS."""
    import DracoPy

    with_colour = len(DracoPy.encode(points, quantization_bits=POSITION_BITS, colors=colours))
    without = len(DracoPy.encode(points, quantization_bits=POSITION_BITS))
    return with_colour, without, with_colour - without


def measure_image(name, rgb, mask, points, colours, what, targets, progress):
    """Every contender on one image."""
    progress(f"{name}: mzc")
    filled = filled_image(rgb, mask)
    item = {"name": name, "what": what, "shape": list(mask.shape), "valid": int(mask.sum()),
            "mzc": mzc_points(rgb, mask, targets), "peers": {}, "lossless": lossless_bytes(filled)}
    for peer in PEERS:
        progress(f"{name}: {peer}")
        item["peers"][peer] = peer_points(peer, filled, rgb, mask)
    item["at_psnr"] = {str(t): {peer: at_psnr(item["peers"][peer], t) for peer in PEERS} for t in targets}
    with_colour, without, difference = draco_colour_bytes(points, colours)
    item["draco"] = {"points": len(points), "with_colour": with_colour, "without": without, "colour": difference}
    return item


# --------------------------------------------------------------------------- report


def markdown(items, settings, targets):
    """The report text."""
    lines = [
        "# Colour: mzc's colour section beside image codecs and Draco (issue 32)",
        "",
        f"`python benchmarks/colour.py{' --quick' if settings['quick'] else ''}` at commit {settings['commit']}, "
        f"{settings['started']} UTC, on {machine()}; {settings['wall_s']:.0f} s.",
        "Package versions: " + ", ".join(f"{k} {v}" for k, v in versions(PACKAGES).items()) + ".",
        "",
        "Colour error over the valid nodes' three channels, in 8-bit levels. The gridded images are "
        "**gridded by this script** (nearest point along z), not by `mzc slice`, which does not sample colour yet. "
        "Peers code the image with invalid nodes filled by mzc's harmonic fill; nobody pays for the mask "
        "(the container codes it). Peer bytes at a PSNR are interpolated log-log between the settings probed.",
        "",
        "| image | nodes (valid) | what |",
        "|---|---|---|",
    ]
    lines += [f"| {i['name']} | {i['shape'][0]} x {i['shape'][1]} ({i['valid']}) | {i['what']} |" for i in items]
    lines += ["", "## Bytes at equal PSNR", "",
              "| image | PSNR target | mzc bytes | mzc PSNR | mzc RMS | " + " | ".join(PEERS) + " | mzc / best peer |",
              "|---|---|---|---|---|" + "---|" * len(PEERS) + "---|"]
    for item in items:
        for point in item["mzc"]:
            if point["target"] == "lossless":
                continue
            peers = item["at_psnr"][str(point["target"])]
            known = [b for b in peers.values() if b]
            lines.append(f"| {item['name']} | {point['target']:g} | {point['bytes']} | "
                         f"{point['colour']['psnr']:.2f} | {point['colour']['rms']:.2f} | "
                         + " | ".join(peer_cell(item, p, point["target"]) for p in PEERS)
                         + f" | {fmt(point['bytes'] / min(known) if known else None)} |")
    lines += ["", "## Lossless and Draco's colour attribute", "",
              "Draco: the valid nodes (the gridded images: the source cloud's points) as a point cloud, positions at "
              f"{POSITION_BITS} bits; its colour bytes are the file with colours minus without (8-bit colours, exact). "
              "mzc at 36 dB codes the grid's colours, not the cloud's: the ratio compares what each stores.",
              "",
              "| image | mzc lossless | " + " | ".join(f"{p} lossless" for p in LOSSLESS)
              + " | Draco points | Draco colour bytes | mzc at 36 dB | mzc 36 dB / Draco colour |",
              "|---|---|" + "---|" * len(LOSSLESS) + "---|---|---|---|"]
    for item in items:
        lossless = next(p for p in item["mzc"] if p["target"] == "lossless")
        at36 = next((p for p in item["mzc"] if p["target"] == 36.0), None)
        draco = item["draco"]
        lines.append(f"| {item['name']} | {lossless['bytes']} | "
                     + " | ".join(str(item["lossless"][p]) for p in LOSSLESS)
                     + f" | {draco['points']} | {draco['colour']} | {at36['bytes'] if at36 else 'n/a'} | "
                     + f"{fmt(at36['bytes'] / draco['colour'] if at36 else None)} |")
    lines += ["", "## mzc's times", "", "| image | target | encode s | decode s |", "|---|---|---|---|"]
    for item in items:
        for point in item["mzc"]:
            lines.append(f"| {item['name']} | {point['target']} | {point['encode_s']:.2f} | {point['decode_s']:.3f} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    arguments = benchmark_parser(__doc__, "one PSNR target (36 dB) and the fuze texture halved").parse_args(argv)
    progress = terminal_progress()
    started = time.perf_counter()
    targets = QUICK_TARGETS if arguments.quick else TARGETS
    settings = {"quick": arguments.quick, "commit": git_commit(), "targets": list(targets),
                "started": f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M}"}
    items = [measure_image(*image, targets, progress) for image in images(arguments.quick)]
    settings["wall_s"] = time.perf_counter() - started
    document = {"settings": settings, "machine": machine(), "versions": versions(PACKAGES), "items": items}
    arguments.out.mkdir(parents=True, exist_ok=True)
    (arguments.out / "colour-results.json").write_text(json.dumps(document, indent=1) + "\n")
    (arguments.out / "colour-results.md").write_text(markdown(items, settings, targets))


if __name__ == "__main__":
    main()
