"""Types of the C extension built from _rows.c (the dwt2d payload decoder's loops): see its comments."""
from typing_extensions import Buffer

OK: int
NO_TABLE: int
RAW_BITS_END: int
NOT_A_SIGN: int
WORDS_LEFT: int
BIT_POSITION: int
DETAIL: int

def read_values(state: Buffer, cursor: Buffer, words: Buffer, bits: Buffer, cumulative: Buffer, width: int,
                model: int, count: int, out: Buffer, /) -> int: ...
def decode_rows(state: Buffer, cursor: Buffer, words: Buffer, bits: Buffer, cumulative: Buffer, width: int,
                rows: int, cols: int, where: Buffer, active: Buffer, thresholds: Buffer, first_model: int,
                parent: Buffer, weights: tuple[int, int, int], first_sign_model: int, sign_contexts: int,
                out: Buffer, /) -> int: ...
def fill_spans(lengths: Buffer, unchanged: Buffer, same: Buffer, gaps: Buffer, rows: int, cols: int,
               valid: Buffer, /) -> int: ...
def decode_flips(state: Buffer, cursor: Buffer, words: Buffer, bits: Buffer, cumulative: Buffer, width: int,
                 rows: int, cols: int, valid: Buffer, /) -> int: ...
