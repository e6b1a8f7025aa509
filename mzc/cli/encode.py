"""``mzc encode``: compress a z-grid with any registered codec.

The command is built from the codec registry each time it runs (``build_command``): one flag
per codec (``--dct``, or ``--poly DEGREE`` for a codec with a selector) and the tuning
options of all codecs, one click option per name. Nothing here knows a particular codec.
"""

import click

from mzc.cli.options import input_argument, output_option, read_grid

HELP = """Compress a z-grid.

--dwt2d, the default, codes the whole grid with a 2D wavelet and an entropy coder,
error-bounded: --max-error E holds at every valid node; --rmse E (RMS distance between
the surfaces) and --size BYTES are targets; without any, --rmse is a tenth of the node
spacing. With --rmse and --size, steps grow where the surface leans from the node lines,
where a value error moves it less along its normal (as 1/sqrt(cos t), up to --slope-limit
times). Errors are along the node lines: heights on planar grids, distances along the rays
of central ones. The thesis's codecs code each row's valid span on its own: a polynomial
of a given degree, or the DFT, DCT or DWT with quality Q (the percentage of coefficients
kept); holes inside a span are recorded and come back invalid. Reads a z-grid (or any mzc
file) from INPUT or stdin; writes the compressed file to -o or stdout. A mesh or point
cloud is sliced first: with --dwt2d --rmse E at the spacing that codes it within E over its
whole surface in the fewest bytes (E as mzc diff --surface measures it), else as mzc slice
cuts it.

\b
  mzc encode --rmse 0.05 face.zg -o face.mzw2
  mzc encode --dwt2d --max-error 0.05 < face.zg > face.mzw2
  mzc encode --dct -q 20 face.zg -o face.mzd
  mzc encode --poly 30 face.zg -o face.mzp
  mzc encode --prior faces.mzp --rmse 0.1 face.zg -o face.mzw2
  mzc encode --rmse 0.08 statue.ply -o statue.mzw2"""
SHORT_NAMES = {"quality": "-q"}


def flag(name):
    """The command-line spelling of an option name: ``max_error`` -> ``--max-error``."""
    return "--" + name.replace("_", "-")


def click_type(option, others=()):
    """The click type of an Option; a range only where every codec that takes it agrees on one."""
    if isinstance(option.type, tuple):
        return click.Choice(sorted({choice for o in (option, *others) for choice in o.type}))
    if any(not isinstance(o.type, tuple) and (o.minimum, o.maximum) != (option.minimum, option.maximum)
           for o in others):
        return {int: click.INT, float: click.FLOAT}.get(option.type, click.STRING)
    if option.type is int:
        return click.IntRange(option.minimum, option.maximum)
    if option.type is float:
        return click.FloatRange(option.minimum, option.maximum, min_open=option.min_open)
    return click.STRING


def codec_flag(codec):
    """The option that selects ``codec``: a flag, or one that takes the selector's value."""
    from mzc.codecs import DEFAULT_CODEC

    text = f"{codec.summary}; {codec.extension}{' [the default]' if codec.name == DEFAULT_CODEC else ''}"
    if codec.selector:
        selector = codec.option(codec.selector)
        return click.Option([flag(codec.name)], type=click_type(selector), metavar=selector.metavar, help=text)
    return click.Option([flag(codec.name)], is_flag=True, default=None, help=text)


def tuning_options(codecs):
    """One click option per tuning option name over all codecs, its help saying which codecs take it."""
    takers = {}
    for codec in codecs:
        for option in codec.options:
            if option.name != codec.selector:
                takers.setdefault(option.name, []).append((codec, option))
    return [tuning_option(name, pairs) for name, pairs in takers.items()]


def tuning_option(name, pairs):
    """The click option of tuning option ``name`` taken by the (codec, Option) ``pairs``."""
    first = pairs[0][1]
    defaults = [(c, o.default) for c, o in pairs if o.default is not None]
    if len({str(d) for _c, d in defaults}) == 1 and len(defaults) == len(pairs):
        default = f" [default: {defaults[0][1]}]"
    else:
        default = f" [default: {', '.join(f'{d} for {flag(c.name)}' for c, d in defaults)}]" if defaults else ""
    codecs = ", ".join(flag(c.name) for c, _o in pairs)
    names = [SHORT_NAMES[name], flag(name)] if name in SHORT_NAMES else [flag(name)]
    if first.type is bool:   # a switch: given or not (None, so that a codec without it is not told False)
        return click.Option([*names, name], is_flag=True, default=None, help=f"{first.help} ({codecs})")
    return click.Option([*names, name], type=click_type(first, [o for _c, o in pairs[1:]]), metavar=first.metavar,
                        help=f"{first.help}{default} ({codecs})")


def chosen_codec(codecs, values):
    """The one codec whose flag was given (none: DEFAULT_CODEC), or a usage error."""
    from mzc.codecs import DEFAULT_CODEC

    chosen = [c for c in codecs if values.get(c.name) not in (None, False)]
    if not chosen:
        chosen = [c for c in codecs if c.name == DEFAULT_CODEC]
    if len(chosen) != 1:
        given = ", ".join(flag(c.name) for c in chosen) or "none"
        known = ", ".join(flag(c.name) + (f" {c.option(c.selector).metavar}" if c.selector else "") for c in codecs)
        raise click.UsageError(f"give exactly one codec: {known} (given: {given})")
    return chosen[0]


def codec_options(codec, values):
    """The options for ``codec`` from the command line's values; one that it does not take is a
    usage error rather than silently ignored (``--dct --wavelet db4`` is a mistake worth telling)."""
    from mzc.errors import MzcError

    taken = {o.name for o in codec.options}
    options = {}
    for name, value in values.items():
        if value is None or name == codec.name:
            continue
        if name not in taken:
            raise click.UsageError(f"{flag(name)} does not apply to {flag(codec.name)}")
        options[name] = value
    if codec.selector:
        options[codec.selector] = values[codec.name]
    try:
        return codec.checked(options)
    except MzcError as error:
        where = flag(error.field) if error.field and error.field != codec.name else flag(codec.name)
        spelled = error.spelled({name: flag(name) for name in (*taken, codec.name)})
        raise click.UsageError(f"{where}: {spelled.message}") from None


def written_by_windows(codec, path, output, options, scheduler=None):
    """Code a GeoTIFF file window by window when ``codec`` can and does (``Codec.window_writer``: a
    raster too large to hold, in tiles; as Dask tasks on ``scheduler`` when given), writing its file
    to ``output`` as it is made; False, with nothing done, when the grid is to be read whole."""
    from mzc.formats import starts_as

    if codec.window_writer is None or not starts_as(path, "tif"):
        return False
    from mzc.errors import about
    from mzc.rasters.windows import GeoTiffSource
    from mzc.streams import display_name, write_output

    source = GeoTiffSource(path, display_name(path))
    try:
        with about(display_name(path), f"encoding it with {codec.name}"):
            chunks = codec.window_writer(source, options, scheduler)
            if chunks is None:
                return False
            write_output(output, chunks)
        return True
    finally:
        source.close()


def build_command():
    """The ``mzc encode`` command over the codecs registered now."""
    from mzc.codecs import codec_names, get_codec

    codecs = [get_codec(name) for name in codec_names()]

    def run(input, output, scheduler, prior, **values):
        from mzc.api import encode
        from mzc.errors import MzcError, about
        from mzc.streams import STDOUT_NAME, check_not_input, display_name, is_terminal, write_output

        codec = chosen_codec(codecs, values)
        options = codec_options(codec, values)
        if is_terminal(output):   # as gzip and xz do: the bytes would only garble the screen
            raise MzcError("compressed data is not written to a terminal: redirect it or give -o FILE",
                           source=STDOUT_NAME)
        check_not_input(output, input)
        if prior is None and written_by_windows(codec, input, output, options, scheduler):
            return
        if scheduler is not None:
            raise click.UsageError("--scheduler codes the tiles of a GeoTIFF file coded in tiles (--dwt2d on a "
                                   "raster of more than one tile, or with --tile N), not this input")
        item = read_grid(input, surfaces=True)
        with about(display_name(input), f"encoding it with {codec.name}"):
            data = encode(item, codec.name, prior=prior, **options)
        write_output(output, data)

    scheduler = click.Option(["--scheduler"], metavar="ADDRESS",
                             help="Code a tiled GeoTIFF's tiles as tasks of this Dask scheduler (tcp://HOST:8786), "
                                  "whose workers read the file themselves: they must see the same path.")
    prior = click.Option(["--prior"], metavar="FILE",
                         help="Code against this prior (mzc train): a grid sliced with --prior FILE is coded alone and "
                              "as its residual from the prior's mean, the smaller written (--dwt2d).")
    command = click.Command("encode", callback=run, help=HELP,
                            params=[*[codec_flag(c) for c in codecs], *tuning_options(codecs), scheduler, prior])
    for decorate in (output_option, input_argument):
        command = decorate(command)
    return command
