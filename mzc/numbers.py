"""Numbers from text tokens, with errors that name the bad token: one home for every reader.

A number is ASCII: Python's ``float`` and ``int`` also take other scripts' digits
(``'٣'``, ``'３'``) and ``_`` separators, which numpy's byte parsers refuse, so those are
refused everywhere rather than read by some readers only (and ``'²'``, which
``str.isdigit`` calls a digit, is refused by all of them anyway).

numpy converts a whole row of tokens at once; only when that fails is the row searched for
the first token that is not a number, so the common case stays vectorised.

Text files may end in NUL bytes (a copy padded to a block: LeePerrySmith.obj, a head scan,
ends with one), which every text reader reads past, as other mesh tools do (``unpadded``).
"""

import re
from collections.abc import Sequence

import numpy as np

from mzc.errors import MzcError

WHOLE_NUMBER = re.compile(r"[0-9]+")
INTEGER = re.compile(r"[+-]?[0-9]{1,18}")


def unpadded(data: bytes) -> bytes:
    """Text ``data`` without the NUL bytes that pad its end; a NUL anywhere else is still there
    to say the data is binary. Copies only a padded file."""
    return data.rstrip(b"\0") if data.endswith(b"\0") else data


def real_array(values, what: str, check_shape=None) -> np.ndarray:
    """``values`` as a float64 array (a float64 array itself, not a copy), or an MzcError naming
    ``what``: complex numbers (a cast would drop their imaginary parts), text, objects and
    ragged lists are no numbers mzc computes with. ``check_shape(shape)`` may refuse the shape
    before anything is converted. A signalling NaN of a float32 file (a depth camera's pixel
    that saw nothing, in any bits) becomes a quiet one without numpy's 'invalid value' warning."""
    try:
        array = np.asarray(values)
    except (TypeError, ValueError):   # a ragged list
        raise MzcError(f"must be an array of numbers, not a {type(values).__name__} of rows of different lengths",
                       field=what) from None
    if array.dtype.kind == "c":
        raise MzcError("complex numbers: mzc computes with real ones", field=what)
    if array.dtype.kind not in "biuf":
        raise MzcError(f"must be numbers, not {array.dtype} values", field=what)
    if check_shape is not None:
        check_shape(array.shape)
    with np.errstate(invalid="ignore"):
        return array.astype(np.float64, copy=False)


def is_number(token: str) -> bool:
    """True when ``token`` is a number in ASCII (``nan`` and ``inf`` included)."""
    if not token.isascii() or "_" in token:
        return False
    try:
        float(token)
    except ValueError:
        return False
    return True


def is_count(token: str) -> bool:
    """True when ``token`` is a whole number >= 0 written in ASCII digits only."""
    return WHOLE_NUMBER.fullmatch(token) is not None


def parse_int(token: str) -> int | None:
    """``token`` as an int when it is one in ASCII decimal digits (at most 18, signed), else None."""
    return int(token) if INTEGER.fullmatch(token) else None


def bad_token(tokens: Sequence[str]) -> int | None:
    """The index of the first token that is not a number, or None."""
    return next((index for index, token in enumerate(tokens) if not is_number(token)), None)


def to_floats(tokens: Sequence[str]) -> np.ndarray:
    """The tokens as a float64 array in one call; a ValueError when one is not a number."""
    joined = "".join(tokens)
    if not joined.isascii() or "_" in joined:
        raise ValueError("not an ASCII number")
    return np.array(tokens, dtype=np.float64)


def floats(tokens: Sequence[str], source: str, line: int, what: str = "value") -> np.ndarray:
    """The tokens as floats, or an MzcError naming the first bad one (``what`` N is not a number)."""
    try:
        return to_floats(tokens)
    except ValueError:
        index = bad_token(tokens)
        if index is None:
            raise
        raise MzcError(f"{what} {index + 1} is not a number: {tokens[index][:40]!r}", source=source,
                       line=line) from None
