"""One item of a batch, done in the process that runs it: a Dask worker, or any Python.

``run_chunk`` is the task a worker gets: many items, one row each. An item that fails
(a bad file, a grid too large, a file mzc cannot slice) becomes a row with its one-line
error; the chunk goes on. The work is that of the filters, called in-process: ``encode``
reads a mesh, cloud or raster, slices it (the options of ``mzc slice``) and encodes it
(those of ``mzc encode``), so its output is byte for byte that of ``mzc slice | mzc
encode``; ``decode`` decodes, optionally densifies and triangulates (``mzc decode | mzc
densify | mzc triangulate``). A GeoTIFF larger than one tile, encoded with no slice option,
goes as ``mzc encode`` takes it: window by window into its tiles (``Codec.window_writer``),
never read whole, the tiles as Dask tasks of the cluster the item runs on.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import stat
import sys
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from mzc.errors import MzcError, MzcWarning, about
from mzc.streams import read_input, write_outputs

ACTIONS = ("encode", "decode")


@dataclass(frozen=True)
class Job:
    """What a batch does to every item: ``action`` (encode or decode) with ``settings``, into the
    folder ``dest``.

    For encode, ``settings`` holds ``codec`` (a registry name), ``codec_options`` (as the codec
    checked them) and ``slice_options`` (those of ``mzc slice`` that were given); for decode,
    ``densify`` (rows to insert), ``method``, ``jump_angle`` and ``format``. ``verify`` also
    measures the whole-surface distance between each input and its decoded output (encode).
    """

    action: str
    dest: str
    settings: dict[str, Any] = field(default_factory=dict)
    verify: bool = False

    @property
    def settings_text(self) -> str:
        """The settings as the manifest records them (and a rerun compares them): compact JSON."""
        return json.dumps(self.settings, sort_keys=True, separators=(",", ":"))


class Timings:
    """Seconds spent in each stage of an item, in the order the stages ran."""

    def __init__(self):
        self.seconds = {}

    @contextmanager
    def stage(self, name):
        started = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] = self.seconds.get(name, 0.0) + time.perf_counter() - started

    def text(self):
        """``read 0.006 slice 0.150 ...``: the manifest's timings column."""
        return " ".join(f"{name} {seconds:.4f}" for name, seconds in self.seconds.items())


def run_chunk(job, tasks):
    """The rows of ``tasks``, a list of (Item, previous row or None): an item whose previous row
    still holds (same input bytes, its output there) is kept as it was, marked ``skipped``."""
    return [run_item(job, item, previous) for item, previous in tasks]


def failed_row(job, item, error, previous=None):
    """The row of an item that failed with ``error`` (one line). When ``previous``, its row from
    an earlier run, says this batch wrote its output and the file is still there, the row keeps
    that output's size: the batch still owns the file, to write it again on a later run."""
    row = {"input": item.source, "output": item.output, "settings": job.settings_text, "status": "failed",
           "error": error}
    if wrote(previous) and os.path.lexists(os.path.join(job.dest, item.output)):
        row["output_bytes"] = previous["output_bytes"]
    return row


def wrote(previous):
    """True when ``previous``, a row from an earlier run, says this batch wrote the item's output:
    it records the output's size (an ok row, or a failed one that kept it)."""
    return bool(previous and previous.get("output_bytes"))


def run_item(job, item, previous=None):
    """The manifest row of one item, done (or found done) now; never raises for a bad input.
    ``previous`` is the manifest's row for the item's output from an earlier run, if any: it
    may say the item is done already, and whether this batch wrote the files there."""
    started = time.perf_counter()
    timings = Timings()
    row = {"input": item.source, "output": item.output, "settings": job.settings_text}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("ignore")
        warnings.simplefilter("always", MzcWarning)
        try:
            with raster_windows(job, item.source) as windows:
                with timings.stage("read"):
                    data = read_input(item.source) if windows is None else None
                    row.update(input_digest(item.source, data))
                if still_done(job, row, previous):
                    return {**previous, "skipped": True}
                row.update(output_bytes=made(job, item, data, windows, row, timings, wrote(previous)), status="ok")
        except MzcError as error:
            row.update(failed_row(job, item, str(error), previous))
        except MemoryError:
            row.update(failed_row(job, item, f"{item.source}: out of memory", previous))
        except Exception as error:  # noqa: BLE001 - one bad item must not stop the batch
            row.update(failed_row(job, item, f"{item.source}: internal error: {type(error).__name__}: {error}",
                                  previous))
    warned = "; ".join(dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, MzcWarning)))
    row.update(warning=warned, seconds=time.perf_counter() - started, timings=timings.text())
    return row


def made(job, item, data, windows, row, timings, owned):
    """Do the item's work and write its files (over files this batch wrote, when ``owned``): by
    windows (``encode_by_windows``) or from its ``data``; the size of its output."""
    if windows is not None:
        return encode_by_windows(job, item, windows, row, timings, owned)
    files = (encode_item if job.action == "encode" else decode_item)(job, item, data, row, timings)
    with timings.stage("write"):
        write_files(job, files, owned)
    return len(files[0][1])


def input_digest(path, data=None):
    """{input_bytes, input_sha256} of an item's input: of its ``data``, or of the file at ``path``
    read a block at a time (a raster coded by windows is never read whole)."""
    if data is not None:
        return {"input_bytes": len(data), "input_sha256": hashlib.sha256(data).hexdigest()}
    from mzc.streams import failure

    try:
        with open(path, "rb") as file:
            digest = hashlib.file_digest(file, "sha256")
            size = os.fstat(file.fileno()).st_size
    except OSError as error:
        raise failure(error, path) from None
    return {"input_bytes": size, "input_sha256": digest.hexdigest()}


@contextmanager
def raster_windows(job, path):
    """The (GeoTiffSource, codec) of an encode item coded window by window, open inside: a GeoTIFF
    file, given no slice option and no ``verify`` (both need the whole grid), that its codec codes
    in tiles (``Codec.window_writer``: larger than one tile); else None, and it is read whole."""
    from mzc.codecs import get_codec
    from mzc.formats import starts_as

    codec = get_codec(job.settings["codec"]) if job.action == "encode" else None
    if codec is None or codec.window_writer is None or job.settings["slice_options"] or job.verify \
            or not starts_as(path, "tif"):
        yield None
        return
    from mzc.codecs.dwt2d.tiles import tile_side
    from mzc.rasters.windows import GeoTiffSource

    source = GeoTiffSource(path, path)
    try:
        tiled = tile_side(source.frame.shape, job.settings["codec_options"].get("tile")) is not None
        yield (source, codec) if tiled else None
    finally:
        source.close()


def encode_by_windows(job, item, windows, row, timings, owned):
    """Encode a raster window by window (``raster_windows``) into the item's output, written as its
    tiles are coded (here, or as Dask tasks of the worker's cluster, ``tile_client``): its size.
    The grid's shape goes in ``row``; its node errors are the tiles', never held at once."""
    source, codec = windows
    row.update(rows=source.frame.rows, cols=source.frame.cols)
    path = os.path.join(job.dest, item.output)
    with timings.stage("encode"), about(item.source, f"encoding it with {codec.name}"), tile_client() as client:
        chunks = codec.window_writer(source, job.settings["codec_options"], client)
        write_chunks(path, chunks, owned)
    return os.path.getsize(path)


@contextmanager
def tile_client():
    """The Dask client of the worker running this item, its thread seceded meanwhile, so that the
    item's tiles run as tasks on its cluster (as ``mzc encode --scheduler`` sends them) and a
    worker waiting for them does not hold a thread they need; None outside a Dask worker (where
    distributed may not even be imported, and is not imported for it)."""
    if "distributed" not in sys.modules:
        yield None
        return
    try:
        from distributed import get_worker, worker_client

        get_worker()
    except (ImportError, ValueError):
        yield None
        return
    with worker_client() as client:
        yield client


def write_chunks(path, chunks, owned):
    """Write an output made in ``chunks`` (a raster's tiles) to ``path`` as they come, folders made
    as needed; a file there that this batch did not write (``owned``) is refused unless it holds
    these very bytes (``already_there``), compared chunk by chunk, never held whole."""
    make_folder(os.path.dirname(path))
    if not os.path.lexists(path) or (owned and stat.S_ISREG(os.lstat(path).st_mode)):
        write_outputs((path, chunks))
    elif not holds_chunks(path, chunks):
        raise not_ours(path)


def holds_chunks(path, chunks):
    """True when the file at ``path`` has exactly the bytes of ``chunks``, in order."""
    try:
        with open(path, "rb") as file:
            return all(file.read(len(chunk)) == chunk for chunk in chunks) and not file.read(1)
    except OSError:
        return False


def still_done(job, row, previous):
    """True when ``previous``, the item's row from an earlier run, holds for the input read now:
    done with the same settings from the same file and bytes, its output of the recorded size
    in place."""
    if not previous or previous.get("status") != "ok" or previous.get("settings") != row["settings"]:
        return False
    if previous.get("input") != row["input"]:
        return False
    if previous.get("input_sha256") != row["input_sha256"]:
        return False
    try:
        return os.path.getsize(os.path.join(job.dest, row["output"])) == int(previous.get("output_bytes", -1))
    except (OSError, ValueError):
        return False


def encode_item(job, item, data, row, timings):
    """A mesh's bytes sliced and encoded: [(the item's output, the compressed file)], with the
    grid and the codec's errors at the grid's nodes (and with ``verify`` the whole-surface
    distance) in ``row``."""
    import numpy as np

    from mzc.codecs import get_codec
    from mzc.colours import warn_uncoded
    from mzc.formats import read
    from mzc.ops.slicing import slice_surface
    from mzc.prior import sliced

    settings, source = job.settings, item.source
    with timings.stage("read"):
        surface = read(data, source, path=source)
    prior = job_prior(settings)
    with timings.stage("slice"), about(source, "slicing it"):
        options = settings["slice_options"]
        grid = slice_surface(surface, **options) if prior is None else \
            sliced(surface, prior, options.get("classes"), options.get("units"))
    codec = get_codec(settings["codec"])
    with timings.stage("encode"), about(source, f"encoding it with {codec.name}"):
        if prior is None:
            output, decoded = codec.encode_with_decoded(grid, **settings["codec_options"])
        else:
            from mzc.prior import encode
            from mzc.prior import read as read_coded

            output = encode(grid, prior, **settings["codec_options"])
            decoded = read_coded(output, source, prior).z
    warn_uncoded(grid, codec, settings["codec_options"])
    valid = grid.valid
    errors = np.abs(decoded[valid] - grid.z[valid])
    row.update(rows=grid.shape[0], cols=grid.shape[1], valid_nodes=int(valid.sum()),
               node_rms=float(np.sqrt(np.mean(errors ** 2))) if errors.size else 0.0,
               node_max_error=float(errors.max()) if errors.size else 0.0)
    if job.verify:
        with timings.stage("verify"), about(source, "measuring the decoded surface"):
            row.update(surface_distances(surface, grid, decoded))
    return [(item.output, output)]


def job_prior(settings):
    """The Prior a batch's ``settings`` name ({path, sha256}), read once in each process; None
    without one. A prior file that changed since the batch started is refused (each item's row)."""
    named = settings.get("prior")
    return None if named is None else loaded_prior(named["path"], named["sha256"])


@functools.lru_cache(maxsize=4)
def loaded_prior(path, digest):
    """The prior at ``path``, whose SHA-256 must be ``digest``."""
    from mzc.prior import as_prior

    prior = as_prior(path)
    if prior.name != digest:
        raise MzcError(f"the prior changed since the batch started (its SHA-256 was {digest})", source=path)
    return prior


def surface_distances(surface, grid, decoded):
    """The whole-surface RMS and Hausdorff distances between ``surface`` (a mesh, or a raster's
    grid) and the mesh of ``grid`` with the ``decoded`` heights (``mzc diff --surface``)."""
    import dataclasses

    from mzc.grid import ZGrid
    from mzc.measure import compare_surfaces
    from mzc.ops.triangulation import grid_to_mesh

    original = grid_to_mesh(surface) if isinstance(surface, ZGrid) else surface
    report = compare_surfaces(original, grid_to_mesh(dataclasses.replace(grid, z=decoded)), surface=True).report
    return {"surface_rms": report["surface_rms"], "surface_hausdorff": report["surface_hausdorff"]}


def decode_item(job, item, data, row, timings):
    """A grid's bytes (an mzc file, or a raster) decoded, densified when asked and triangulated:
    [(the item's output, the mesh file)]; or, for a raster format, the raster's files
    (``mzc.rasters.raster_files``)."""
    from mzc.formats import GRIDS, named, read

    settings, source = job.settings, item.source
    prior = job_prior(settings)
    with timings.stage("decode"), about(source, "decoding it"):
        if prior is None:
            grid = read(data, source, GRIDS, path=source)
        else:
            from mzc.prior import read as read_coded

            grid = read_coded(data, source, prior, source)
    row.update(rows=grid.shape[0], cols=grid.shape[1], valid_nodes=int(grid.valid.sum()))
    if settings["densify"]:
        from mzc.ops.densify import densify_grid

        with timings.stage("densify"), about(source, f"densifying it ({settings['method']}, "
                                                     f"n = {settings['densify']})"):
            grid = densify_grid(grid, settings["densify"], settings["method"], jump_angle=settings["jump_angle"])
    if named(settings["format"]).kind == "raster":
        from mzc.rasters import raster_files

        with timings.stage("raster"), about(source, f"writing it as {settings['format']}"):
            return raster_files(item.output, grid, settings["format"], options=settings.get("co"),
                                cog=settings.get("cog", False))
    from mzc.meshes import mesh_to_bytes
    from mzc.ops.simplify import rebuilt

    with timings.stage("triangulate"), about(source, "triangulating it"):   # near the source's vertex count
        return [(item.output, mesh_to_bytes(rebuilt(grid, settings["jump_angle"]), settings["format"]))]


def write_files(job, files, owned):
    """Write an item's [(name, bytes)] under the destination, atomically (none of them on a
    failure), folders made as needed. A file there is written over only when ``owned`` (the
    manifest says this batch wrote the item's output); see ``already_there``."""
    outputs = [(os.path.join(job.dest, name), data) for name, data in files]
    outputs = [(path, data) for path, data in outputs if not already_there(path, data, owned)]
    for folder in dict.fromkeys(os.path.dirname(path) for path, _data in outputs):
        make_folder(folder)
    write_outputs(*outputs)


def make_folder(folder):
    """Make ``folder`` and its parents, as needed, or say in one line why not."""
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as error:
        raise MzcError(f"cannot make the folder: {error.strerror or error}", source=folder) from None


def already_there(path, data, owned):
    """True when the file at ``path`` holds ``data`` already, so there is nothing to write (a
    worker that died after writing it left it, and its chunk ran again); False when ``path``
    may be written: nothing is there, or a regular file this batch wrote (``owned``). Any other
    file is refused (an MzcError): a batch never writes over a file it did not write."""
    try:
        info = os.lstat(path)
    except OSError:   # nothing there, or a path the write will refuse in its words
        return False
    if owned and stat.S_ISREG(info.st_mode):
        return False
    if holds(path, data):
        return True
    raise not_ours(path)


def not_ours(path):
    """The error of a file in the way that this batch did not write: a batch never writes over one."""
    return MzcError("is there already and was not written by this batch (no row of its manifest says so): move "
                    "it away or give another -o", source=path)


def holds(path, data):
    """True when the file at ``path`` (followed, if a link) has exactly the bytes ``data``."""
    try:
        with open(path, "rb") as file:
            return os.fstat(file.fileno()).st_size == len(data) and file.read() == data
    except OSError:
        return False
