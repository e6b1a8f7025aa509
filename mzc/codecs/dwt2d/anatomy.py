"""Where the bytes of a dwt2d file go: header, mask, entropy tables, coefficients (issue 33's
measure of a small file's fixed cost, benchmarks/fixed_cost.py).

The mask's symbols share the rANS words with the bands', so its share is their ideal cost under
the file's own models (bits of -log2 of each class's probability, plus its raw bits); the
coefficients are the rest of the payload.
"""

import numpy as np

from mzc.codecs.dwt2d import encode_mask, flips
from mzc.codecs.dwt2d import entropy as en
from mzc.errors import MzcError


def parts(data):
    """{header, mask, tables, coefficients: bytes} of a whole (not tiled) dwt2d file, summing to its size."""
    from mzc import decode
    from mzc.codecs.dwt2d import compact
    from mzc.formats.header import read_header

    if compact.major(data) == compact.PROGRESSIVE_MAJOR:
        raise MzcError("a progressive file (9.0) has a payload a level: measure the 8.0 file of the grid",
                       field="data")
    grid = decode(data)
    if compact.is_compact(data):   # the sections' tags, lengths and CRCs count as header
        body = compact.read(data, "<bytes>")[1]
    else:
        body = read_header(data, "<bytes>", "dwt2d", 99, binary=True)[1]
    decoder = en.Decoder(body, "<bytes>", parametric=compact.is_compact(data),
                         short=compact.major(data) == compact.TIGHT_MAJOR)
    tables = decoder.position - len(en.varint(len(decoder.tables)))
    if (compact.major(data) or 0) >= 8:   # the predicted flips: no tables, every bit in the rANS words
        mask = flips.ideal_bits(grid.valid) / 8
    else:
        mask = mask_bits(grid.valid, decoder.tables) / 8
    return {"header": len(data) - len(body), "mask": round(mask), "tables": tables,
            "coefficients": len(body) - tables - round(mask)}


def mask_bits(valid, tables):
    """Ideal bits of the mask's symbols under ``tables`` (frequencies by model id), raw bits included."""
    encoder = en.Encoder()
    encode_mask(encoder, valid)
    models, values = np.concatenate(encoder.models), np.concatenate(encoder.values)
    cls = en.classes(values)
    padded = np.ones((len(tables), en.MAX_CLASSES))
    for model, table in enumerate(tables):
        padded[model, :len(table)] = table
    return float(-np.log2(padded[models, cls] / (1 << en.TABLE_BITS)).sum() + cls.sum())
