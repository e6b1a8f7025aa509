"""What a codec is: a name, a format version, the options it takes, and encode/decode.

In the manner of numcodecs, a codec is one object that says everything the rest of mzc
needs: ``mzc encode`` builds its flag and tuning options from ``options`` and ``selector``,
``mzc decode`` and ``mzc info`` find it by the ``kind`` of a file's magic line, and the
contract tests (tests/codec_contract.py) run it through round trips, its spec page's worked
example, hostile input and its stored fixtures. Adding a codec is one module that builds a
``Codec`` and registers it (``mzc.codecs.register_codec``), plus its spec page.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from mzc.errors import MzcError

if TYPE_CHECKING:
    import numpy as np

    from mzc.grid import ZGrid


@dataclass(frozen=True)
class Option:
    """One tuning option of a codec: its type (int, float, str, bool for a switch, or a tuple of the choices), its
    default (None: unset unless given), its range and the help the command line shows."""

    name: str
    type: type | tuple[str, ...]
    default: Any = None
    minimum: float | None = None
    maximum: float | None = None
    min_open: bool = False
    help: str = ""
    metavar: str | None = None

    def check(self, value: Any) -> Any:
        """``value`` converted to the option's type, or an MzcError naming the option."""
        if isinstance(self.type, tuple):
            if value not in self.type:
                raise MzcError(f"{value!r} is not one of {', '.join(self.type)}", field=self.name)
            return value
        if self.type is bool:   # a switch (a command-line flag): True or False, nothing that would pass for one
            if not isinstance(value, bool):
                raise MzcError(f"must be True or False, not {value!r}", field=self.name)
            return value
        if self.type is str:
            if not isinstance(value, str):
                raise MzcError(f"must be text, not {value!r}", field=self.name)
            return value
        return self.in_range(self.number(value))

    def number(self, value: Any) -> int | float:
        """``value`` as this option's int or float: a bool, a fraction for an int or a non-number is refused."""
        whole = self.type is int
        try:
            ok = not isinstance(value, bool) and (float(value) == int(value) if whole else math.isfinite(float(value)))
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise MzcError(f"must be {'a whole number' if whole else 'a finite number'}, not {value!r}",
                           field=self.name)
        return int(value) if whole else float(value)

    def in_range(self, value: int | float) -> int | float:
        """``value`` if it lies within the option's range."""
        low, high = self.minimum, self.maximum
        too_low = low is not None and (value <= low if self.min_open else value < low)
        if too_low or (high is not None and value > high):
            raise MzcError(f"{value:g} is outside {self.range_text()}", field=self.name)
        return value

    def range_text(self) -> str:
        """The range in words: ``1..100``, ``> 0``, ``>= 1``."""
        if self.minimum is not None and self.maximum is not None:
            return f"{self.minimum:g}..{self.maximum:g}"
        if self.minimum is not None:
            return f"{'>' if self.min_open else '>='} {self.minimum:g}"
        return f"<= {self.maximum:g}" if self.maximum is not None else "any value"


@dataclass(frozen=True)
class Codec:
    """A codec of z-grids: ``writer(grid, **options) -> bytes`` and ``reader(data, source) -> ZGrid``.

    ``name`` is its registry key and command-line flag; ``kind`` the word after ``mzc-`` in the
    magic line of its files; ``version`` the newest format version it writes and
    ``oldest_major`` the oldest major version it reads; ``selector`` names the option whose
    value comes with the flag itself (``--poly DEGREE``); ``spec`` is its spec page.
    ``check_options`` enforces rules between options (dwt2d: exactly one target);
    ``example`` holds the options of a typical use (the contract tests encode with them);
    ``writer_with_decoded(grid, **options) -> (bytes, heights)``, for a codec that reconstructs
    the grid as it codes, also gives the heights a decoder will get (``encode_with_decoded``);
    ``window_writer(source, options, scheduler)``, for a codec that codes a grid too large to hold
    a window at a time (a raster read by windows, mzc.rasters.windows; on the Dask ``scheduler`` at
    that address, when not None), gives the file's bytes in chunks, or None when it codes that grid
    whole (the caller then reads it whole); ``keeps_colour(grid, options)`` says how much of a
    grid's colours its file carries: 0 none, 1 the nodes', K the colours K times finer than the
    nodes (mzc.colours.warn_uncoded names what is not carried).
    """

    name: str
    writer: Callable[..., bytes]
    reader: Callable[[bytes, str], ZGrid]
    version: tuple[int, int] = (1, 0)
    kind: str = ""
    extension: str = ""
    summary: str = ""
    spec: str | None = None
    options: tuple[Option, ...] = ()
    selector: str | None = None
    oldest_major: int = 1
    example: dict[str, Any] = field(default_factory=dict)
    check_options: Callable[[dict[str, Any]], None] = field(default=lambda options: None)
    writer_with_decoded: Callable[..., tuple[bytes, np.ndarray]] | None = None
    window_writer: Callable[[Any, dict[str, Any], str | None], Iterator[bytes] | None] | None = None
    keeps_colour: Callable[[ZGrid, Mapping[str, Any]], int] = field(default=lambda grid, options: 0)

    def __post_init__(self) -> None:
        if not self.kind:
            object.__setattr__(self, "kind", self.name)

    def option(self, name: str) -> Option:
        """The option called ``name``."""
        return next(o for o in self.options if o.name == name)

    def checked(self, options: Mapping[str, Any]) -> dict[str, Any]:
        """``options`` checked, converted and completed with the defaults, as the writer takes them."""
        known = {o.name for o in self.options}
        unknown = sorted(set(options) - known)
        if unknown:
            raise MzcError(f"codec {self.name} takes no option {unknown[0]!r} (it takes: {', '.join(sorted(known))})",
                           field=unknown[0])
        given = {name: value for name, value in options.items() if value is not None}
        values = {o.name: o.check(given[o.name]) if o.name in given else o.default for o in self.options}
        self.check_options(values)
        return {name: value for name, value in values.items() if value is not None}

    def encode(self, grid: ZGrid, **options: Any) -> bytes:
        """The bytes of ``grid`` coded with ``options`` (checked; defaults filled in).

        Heights and coordinates too large to code (mzc.limits) are refused rather than written as
        numbers no reader takes back; and since a lossy codec's decoded heights may exceed its
        input's (a DCT's dropped coefficients, by up to LOSSY_GROWTH times), an input that near
        the limit has its file decoded and refused if a reader would refuse it."""
        from mzc.limits import LOSSY_GROWTH, MAX_MAGNITUDE, check_grid_magnitudes, check_magnitude

        largest = check_grid_magnitudes(grid)
        data = self.writer(grid, **self.checked(options))
        if largest > MAX_MAGNITUDE / LOSSY_GROWTH:
            check_magnitude(self.decode(data).z, "decoded heights", field="z")
        return data

    def encode_with_decoded(self, grid: ZGrid, **options: Any) -> tuple[bytes, np.ndarray]:
        """The bytes of ``grid`` and the heights a decoder gets from them (NaN off the valid nodes),
        so a caller can report the errors of what it wrote: from the writer where it knows them
        (checked as ``encode`` checks them), else by decoding the bytes."""
        from mzc.limits import check_grid_magnitudes, check_magnitude

        if self.writer_with_decoded is None:
            data = self.encode(grid, **options)
            return data, self.decode(data).z
        check_grid_magnitudes(grid)
        data, decoded = self.writer_with_decoded(grid, **self.checked(options))
        check_magnitude(decoded, "decoded heights", field="z")
        return data, decoded

    def decode(self, data: bytes, source: str = "<bytes>") -> ZGrid:
        """The z-grid of a file of this codec; ``source`` names it in error messages."""
        return self.reader(data, source)

    read = decode   # a codec reads its files as every format's module does (mzc.formats)
