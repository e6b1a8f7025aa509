"""Colours: 8-bit RGB values beside points and grid nodes, one home for checking them and for
turning what files hold (8- or 16-bit integers, floats in 0..1 or 0..255, PCL's packed ``rgb``)
into them.

mzc keeps colour as (..., 3) uint8: red, green, blue, each 0..255, as PLY's ``uchar red green
blue``, a PNG and Draco's 8-bit colour attribute hold it. An alpha channel is read past.
"""

import numpy as np

from mzc.errors import MzcError

CHANNELS = 3


def colour_array(values, shape, field="colors"):
    """``values`` as a uint8 array of ``shape`` (the last axis CHANNELS): integers 0..255 (any
    integer type, or floats that are whole numbers in that range), refused otherwise with an
    MzcError naming ``field``: a colour outside 0..255 would wrap round in a cast."""
    try:
        array = np.asarray(values)
    except (TypeError, ValueError):
        raise MzcError("must be an array of 0..255 integers", field=field) from None
    if array.dtype.kind not in "biuf":
        raise MzcError(f"must be 0..255 integers, not {array.dtype} values", field=field)
    if array.size != int(np.prod(shape)):
        raise MzcError(f"must be an array of shape {shape}, not one of shape {array.shape}", field=field)
    if array.dtype == np.uint8:
        return array.reshape(shape)
    with np.errstate(invalid="ignore"):
        bad = ~((array >= 0) & (array <= 255) & (array == np.round(array)))
    if bad.any():
        raise MzcError(f"{array.reshape(-1)[np.flatnonzero(bad)[0]]!r} is no 0..255 colour value", field=field)
    return array.astype(np.uint8).reshape(shape)


def to_8_bits(values, bits=None):
    """(n, 3) uint8 colours of (n, 3) ``values`` as a file holds them: integers of ``bits`` bits
    (the type the file declares, whatever array holds them: an ascii file's are floats) 8-bit
    as they are, wider ones scaled from their range (16-bit LAS and PLY colours); with
    ``bits`` None (floats: PLY's ``float red``, OBJ's ``v x y z r g b``) 0..1 fractions,
    unless one exceeds 1, when they are 0..255 levels (OBJ files of some exporters). NaN is 0,
    and values out of range are clipped."""
    values = np.nan_to_num(np.asarray(values, dtype=np.float64), nan=0.0)
    if bits is not None:
        scale = 255 / (2.0 ** bits - 1)
    else:
        scale = 1.0 if values.size and np.max(values) > 1 else 255.0
    return np.clip(np.round(values * scale), 0, 255).astype(np.uint8)


def unpack_rgb(values):
    """(n, 3) uint8 colours of PCL's packed ``rgb``/``rgba`` field: each point's four bytes (a
    float32 or uint32 as PCL stores it) hold blue, green, red (and alpha) from the lowest byte."""
    packed = np.ascontiguousarray(values).reshape(-1)
    if packed.dtype.itemsize != 4:
        raise MzcError(f"a packed rgb field holds 4 bytes a point, not {packed.dtype.itemsize}", field="rgb")
    return packed.view("<u4").view(np.uint8).reshape(-1, 4)[:, 2::-1].copy()


KEEPERS = "the z-grid and a dwt2d file keep them"   # the files that keep a grid's nodes' colours


def warn_uncoded(grid, codec, options):
    """One MzcWarning when ``grid`` has colours that the file ``codec`` (a Codec) writes with
    ``options`` does not carry (the row codecs, zarr: ``Codec.keeps_colour``), or not as finely (a
    dwt2d file in tiles keeps the nodes'), so that they are not lost without a word (issue 32)."""
    if grid.colors is None:
        return
    kept = codec.keeps_colour(grid, options)
    if not kept:
        warn_not_kept("the nodes' colours", f"this mzc-{codec.kind} file codes the shape alone; {KEEPERS}")
    elif kept < grid.colour_scale:
        warn_not_kept(f"the colours {grid.colour_scale} times finer than the nodes",
                      f"this mzc-{codec.kind} file in tiles keeps the nodes' colours; --tile 0 codes it whole, "
                      "with them")


def warn_raster_drops(raster):
    """One MzcWarning that a ``raster`` (tif or asc) written of a grid with colours holds its
    heights alone (issue 32: nothing dropped without a word)."""
    name = {"tif": "GeoTIFF", "asc": "ESRI ASCII grid"}.get(raster, f"{raster} raster")
    warn_not_kept("the nodes' colours", f"a {name} holds the heights alone; {KEEPERS}")


def warn_not_kept(what, why):
    """The MzcWarning "not kept: WHAT (WHY)" of colours a file leaves out."""
    import warnings

    from mzc.errors import MzcWarning

    warnings.warn(MzcWarning(f"not kept: {what} ({why})"), stacklevel=3)
