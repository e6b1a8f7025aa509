"""A property-based fuzz of every reader (tests/fuzz/readers.py): real files of each kind (every
mesh and cloud format, the rasters, the z-grid, every compressed kind and the thesis's files),
mutated by hypothesis, each read in a worker process under RLIMIT_AS and a deadline. An input
must be read into a sane result or refused in one MzcError line, without a warning but mzc's own, in under
SECONDS and under PEAK bytes of allocations. MZC_FUZZ_EXAMPLES sets the inputs per kind (200 in
the suite, 4,400 inputs in about 25 s; more for a longer run)."""

import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fuzz.readers import KINDS, Worker, mutate, seeds

EXAMPLES = int(os.environ.get("MZC_FUZZ_EXAMPLES", "200"))
SECONDS = 10               # a reader on these few-KB inputs takes milliseconds; a busy machine, a margin
PEAK = 256 << 20           # bytes: the seeds are at most 93 KB, and what a mutation declares is within mzc.limits
NEEDS = {"las": "laspy", "tif": "rasterio"}


@pytest.fixture(scope="module")
def worker():
    """One worker process for the module's inputs."""
    started = Worker()
    yield started
    started.close()


class Choices:
    """``mutate``'s choices drawn by hypothesis."""

    def __init__(self, draw):
        self.draw = draw

    def integer(self, low, high):
        """A whole number from ``low`` to ``high``."""
        return self.draw(st.integers(low, high))

    def pick(self, options):
        """One of ``options``."""
        return self.draw(st.sampled_from(options))


def kept_bounds(kind, result):
    """The promise for one input's outcome in the worker."""
    assert result["outcome"] in ("ok", "refused"), f"{kind}: {result['outcome']}: {result['detail']}"
    assert result["seconds"] < SECONDS and result["peak"] < PEAK, (kind, result)


@pytest.mark.parametrize("kind", KINDS)
def test_every_seed_is_read(kind, worker):
    if kind in NEEDS:
        pytest.importorskip(NEEDS[kind])
    for data in seeds(kind):
        result = worker.read(kind, data)
        assert result["outcome"] == "ok", result["detail"]


@pytest.mark.parametrize("kind", KINDS)
def test_mutated_files_are_read_or_refused_in_bounded_time_and_memory(kind, worker):
    if kind in NEEDS:
        pytest.importorskip(NEEDS[kind])
    originals = seeds(kind)

    @given(st.data())
    @settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    def check(data):
        mutated = mutate(data.draw(st.sampled_from(originals)), Choices(data.draw))
        kept_bounds(kind, worker.read(kind, mutated))

    check()
