"""``mzc batch encode|decode``: the filters over whole archives, on Dask (mzc.batch)."""

import click

from mzc.cli.densify import DEFAULT_METHOD, METHODS
from mzc.cli.options import (
    RASTER_FORMATS,
    co_option,
    cog_option,
    given_geotiff_options,
    jump_angle_option,
    with_options,
)
from mzc.cli.triangulate import FORMATS
from mzc.limits import MAX_INSERTED

SOURCES_HELP = """SOURCES are files, folders (walked recursively for the job's files), glob
patterns ('scans/**/*.ply', quoted) and lists of paths (@LIST, one per line; @- reads
stdin). Outputs keep the inputs' layout under DEST, and DEST/manifest.csv gets a row per
item: input bytes and SHA-256, output bytes, grid, settings, errors, seconds, status and
the error of a failed item. A rerun skips the items whose row still holds (same input
bytes and settings, the output in place), so a stopped batch resumes. A batch writes over
only the files it wrote (any other file at an output is kept, and its item fails), and
holds DEST alone: a second batch into it meanwhile is refused. The work runs on a local
Dask cluster (one worker process per core) unless --scheduler names one; a failed item is
recorded and the rest go on; the exit status is 1 when any item failed."""

batch_options = [
    click.argument("sources", nargs=-1, required=True, metavar="SOURCES..."),
    click.option("-o", "--output", "dest", required=True, metavar="DEST", help="The folder to write into."),
    click.option("--scheduler", metavar="ADDRESS",
                 help="A running Dask scheduler (tcp://host:8786) whose workers see the same paths "
                      "[default: a local cluster for the run]."),
    click.option("--workers", type=click.IntRange(1, 1024), metavar="N",
                 help="Worker processes of the local cluster [default: one per core]."),
    click.option("--chunk-size", type=click.IntRange(1, 100_000), metavar="N",
                 help="Items per Dask task [default: about 32 tasks per worker]."),
]


def build_command():
    """The ``mzc batch`` group: encode (built from the codec registry, like ``mzc encode``) and decode."""
    group = click.Group("batch", help="Run slice+encode or decode+triangulate over whole archives, on Dask.")
    group.add_command(build_encode())
    group.add_command(decode)
    return group


def build_encode():
    """``mzc batch encode``: slice and encode every mesh, cloud and raster, with the options of
    slice and encode."""
    from mzc.cli.encode import chosen_codec, codec_flag, codec_options, tuning_options
    from mzc.cli.slice import SLICE_NAMES, SLICE_OPTIONS, check_slice_options
    from mzc.codecs import codec_names, get_codec

    codecs = [get_codec(name) for name in codec_names()]

    def run(sources, dest, scheduler, workers, chunk_size, verify, prior, **values):
        from mzc.api import batch_encode

        slicing = {name: values.pop(name) for name in SLICE_NAMES}
        check_slice_options(slicing["d1"], slicing["d2"], slicing["rows"], slicing["cols"])
        codec = chosen_codec(codecs, values)
        options = codec_options(codec, values)
        report(batch_encode(sources, dest, codec.name, verify=verify, scheduler=scheduler, workers=workers,
                            chunk_size=chunk_size, listener=terminal_progress(), slice_options=slicing,
                            prior=prior, **options))

    params = [*[codec_flag(c) for c in codecs], *tuning_options(codecs)]
    command = click.Command("encode", callback=run, params=params, help=ENCODE_HELP)
    verify = click.option("--verify", is_flag=True, help="Measure each decoded surface against its input's.")
    prior = click.option("--prior", metavar="FILE",
                         help="Cut every surface on this prior's lattice and code it against it (mzc train; "
                              "--dwt2d), as 'mzc slice --prior | mzc encode --prior'; the workers read it here.")
    return with_options([*batch_options, *SLICE_OPTIONS, verify, prior], command)


ENCODE_HELP = f"""Slice and encode every mesh, point cloud and raster of SOURCES into DEST.

Each is sliced with the options of 'mzc slice' (a raster is its own grid) and encoded with
those of 'mzc encode', in-process: the output is byte for byte that of 'mzc slice | mzc
encode'. --verify also measures each decoded surface against the input's (RMS and
Hausdorff, as 'mzc diff --surface').

{SOURCES_HELP}

\b
  mzc batch encode scans/ -o archive/ --dwt2d --rmse 0.05
  mzc batch encode @todo.txt -o archive/ --dwt2d --max-error 0.1 --scheduler tcp://head:8786"""


@click.command("decode", help=f"""Decode every mzc file of SOURCES into a mesh or raster in DEST.

Each file is decoded, densified with -n/--densify N rows between planes when asked (as 'mzc
densify'), and triangulated (as 'mzc triangulate') into --format; with --format tif or asc,
written as a GeoTIFF or an ESRI ASCII grid (its CRS in a .prj beside it) instead, as 'mzc
decode --format' writes the grids of rasters.

{SOURCES_HELP}

\b
  mzc batch decode archive/ -o meshes/ --densify 3 --format ply
  mzc batch decode dems.mzw2/ -o dems/ --format tif""")
@click.option("-n", "--densify", type=click.IntRange(0, MAX_INSERTED), default=0, show_default=True, metavar="N",
              help="Rows to insert between each pair of rows (mzc densify -n).")
@click.option("--method", type=click.Choice(METHODS), default=DEFAULT_METHOD,
              show_default=True, help="How densify fills the inserted rows.")
@click.option("--format", "file_format", type=click.Choice([*FORMATS, *RASTER_FORMATS]), default="ply",
              show_default=True, help="Mesh format of the outputs, or tif or asc: rasters.")
@jump_angle_option
@click.option("--prior", metavar="FILE", help="The prior (mzc train) residual files were coded against; the "
                                              "workers read it here.")
@co_option
@cog_option
def decode(densify, method, file_format, jump_angle, prior, sources, dest, scheduler, workers, chunk_size):
    from mzc.api import batch_decode

    co, cog = given_geotiff_options()
    report(batch_decode(sources, dest, densify=densify, method=method, file_format=file_format,
                        jump_angle=jump_angle, creation_options=co, cog=cog, scheduler=scheduler, workers=workers,
                        chunk_size=chunk_size, listener=terminal_progress(), prior=prior))


decode = with_options(batch_options, decode)


def terminal_progress():
    """The listener of a command: failed items' errors on stderr, and a bar when it is a terminal."""
    import sys

    from mzc.batch.engine import TerminalProgress

    return TerminalProgress(sys.stderr, bar=sys.stderr.isatty())


def report(summary):
    """The summary as the last line on stderr; exit status 1 when any item failed."""
    import sys

    click.echo(("\r\x1b[K" if sys.stderr.isatty() else "") + summary.line(), err=True)
    if summary.failed:
        raise click.exceptions.Exit(1)
