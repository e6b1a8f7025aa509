"""Numbers from text tokens, with errors that name the bad token: one home for every reader.

numpy converts a whole row of tokens at once; only when that fails is the row searched for
the first token that is not a number, so the common case stays vectorised.
"""

from collections.abc import Sequence

import numpy as np

from mzc.errors import MzcError


def bad_token(tokens: Sequence[str]) -> int | None:
    """The index of the first token that is not a number, or None."""
    for index, token in enumerate(tokens):
        try:
            float(token)
        except ValueError:
            return index
    return None


def floats(tokens: Sequence[str], source: str, line: int, what: str = "value") -> np.ndarray:
    """The tokens as floats, or an MzcError naming the first bad one (``what`` N is not a number)."""
    try:
        return np.array(tokens, dtype=float)
    except ValueError:
        index = bad_token(tokens)
        if index is None:
            raise
        raise MzcError(f"{what} {index + 1} is not a number: {tokens[index][:40]!r}", source=source,
                       line=line) from None
