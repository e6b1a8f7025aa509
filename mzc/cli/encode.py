"""``mzc encode``: compress a z-grid with one of the thesis's per-row codecs.

The codec table below is the only place that knows the codecs: each entry names its
format module, the option that selects it, and the tuning options it accepts. Adding a
codec (e.g. ``--dwt2d``) is one entry, its selecting option and, if it brings new tuning
options, their decorators.
"""

from dataclasses import dataclass

import click

from mzc.cli.options import input_argument, output_option, read_grid


@dataclass(frozen=True)
class Codec:
    """A codec of ``mzc encode``: format module ``kind``, the tuning options it takes, and the
    keyword that receives the selecting option's value (``--poly DEGREE`` -> degree)."""

    kind: str
    settings: tuple
    value_keyword: str | None = None
    keywords: tuple = ()  # (option, keyword of write) pairs where the two names differ


CODECS = {
    "poly": Codec("poly", ("basis", "precision"), value_keyword="degree"),
    "dft": Codec("dft", ("quality", "precision")),
    "dct": Codec("dct", ("quality", "precision")),
    "dwt": Codec("dwt", ("quality", "wavelet", "level", "precision")),
    "dwt2d": Codec("dwt2d", ("max_error", "rmse", "size", "wavelet", "level", "slope_limit"),
                   keywords=(("level", "levels"),)),
}
DEFAULTS = {"quality": 100, "precision": 4}


def chosen_codec(selections):
    """The one codec whose option was given, or a usage error."""
    chosen = [name for name, value in selections.items() if value not in (None, False)]
    if len(chosen) != 1:
        given = ", ".join(f"--{name}" for name in chosen) or "none"
        raise click.UsageError(f"give exactly one codec: --poly DEGREE, --dft, --dct, --dwt or --dwt2d "
                               f"(given: {given})")
    return chosen[0]


def codec_arguments(name, value, settings):
    """Keyword arguments for the codec's ``write``: its own settings, defaults filled in.

    A tuning option that the codec does not use is a usage error rather than silently
    ignored (``--dct --wavelet db4`` is a mistake worth telling).
    """
    codec = CODECS[name]
    for setting, given in settings.items():
        if given is not None and setting not in codec.settings:
            raise click.UsageError(f"--{setting} does not apply to --{name}")
    renamed = dict(codec.keywords)
    arguments = {renamed.get(s, s): settings[s] if settings[s] is not None else DEFAULTS[s]
                 for s in codec.settings if settings[s] is not None or s in DEFAULTS}
    if codec.value_keyword:
        arguments[codec.value_keyword] = value
    return arguments


@click.command(help="""Compress a z-grid.

The thesis's codecs code each row's valid span on its own: a polynomial of a given
degree, or the DFT, DCT or DWT with quality Q (the percentage of coefficients kept).
Holes inside a span are recorded and come back invalid. --dwt2d codes the whole grid
with a 2D wavelet and an entropy coder, error-bounded: --max-error E holds at every
valid node; --rmse E (RMS distance between the surfaces) and --size BYTES are targets.
With --rmse and --size, steps grow where the surface leans from the node lines, where a
value error moves it less along its normal (as 1/sqrt(cos t), up to --slope-limit times).
Errors are along the node lines: heights on planar grids, distances along the rays of
central ones. Reads a z-grid (or any mzc file)
from INPUT or stdin; writes the compressed file to -o or stdout.

\b
  mzc encode --dct -q 20 face.zg -o face.mzd
  mzc encode --dwt -q 10 --wavelet db2 < face.zg > face.mzw
  mzc encode --poly 30 face.zg -o face.mzp
  mzc encode --dwt2d --max-error 0.05 face.zg -o face.mzw2""")
@input_argument
@output_option
@click.option("--poly", type=click.IntRange(0, 10_000), metavar="DEGREE",
              help="Polynomial of DEGREE per row (Ch. 5); .mzp")
@click.option("--dft", is_flag=True, help="Discrete Fourier transform (Ch. 6); .mzf")
@click.option("--dct", is_flag=True, help="Discrete cosine transform (§7.2.2); .mzd")
@click.option("--dwt", is_flag=True, help="Discrete wavelet transform (§7.2.3); .mzw")
@click.option("--dwt2d", is_flag=True, help="2D wavelet of the whole grid, entropy coded, error-bounded; .mzw2")
@click.option("-q", "--quality", type=click.IntRange(1, 100), metavar="Q",
              help="Percentage of coefficients kept, 1..100 [default: 100]; not for --poly.")
@click.option("--wavelet", metavar="NAME",
              help="Wavelet, e.g. db1, db2, sym4 [default: db1 for --dwt, bior4.4 for --dwt2d].")
@click.option("--level", type=click.IntRange(0, 32), metavar="N",
              help="Wavelet levels [default: 3 for --dwt, capped per row; chosen from the grid for --dwt2d].")
@click.option("--basis", type=click.Choice(["chebyshev", "power"]),
              help="Polynomial basis: chebyshev (stable) or power (the thesis's polyfit) [default: chebyshev].")
@click.option("--max-error", type=click.FloatRange(min=0, min_open=True), metavar="E",
              help="--dwt2d: |decoded - input| <= E at every valid node.")
@click.option("--rmse", type=click.FloatRange(min=0, min_open=True), metavar="E",
              help="--dwt2d: aim at this RMS surface error (value error times cos of the lean).")
@click.option("--size", type=click.IntRange(min=1), metavar="BYTES", help="--dwt2d: aim at this file size.")
@click.option("--slope-limit", type=click.FloatRange(min=1), metavar="F",
              help="--dwt2d: steps grow as 1/sqrt(cos lean) up to F times; 1 = equal steps "
                   "[default: 2 for --rmse and --size, 1 for --max-error].")
@click.option("--precision", type=click.IntRange(0, 17), metavar="DIGITS",
              help="Decimals of the written coefficients [default: 4].")
def command(input, output, poly, dft, dct, dwt, dwt2d, **settings):
    from mzc.formats import module_for
    from mzc.streams import check_not_input, write_output

    selections = {"poly": poly, "dft": dft, "dct": dct, "dwt": dwt, "dwt2d": dwt2d}
    name = chosen_codec(selections)
    arguments = codec_arguments(name, selections[name], settings)
    if name == "dwt2d" and sum(arguments.get(k) is not None for k in ("max_error", "rmse", "size")) != 1:
        raise click.UsageError("--dwt2d needs exactly one of --max-error E, --rmse E or --size BYTES")
    check_not_input(output, input)
    grid = read_grid(input)
    write_output(output, module_for(CODECS[name].kind).write(grid, **arguments))
