"""Dask clients for mzc's work spread over processes or machines (``mzc batch`` and the tiles of
``mzc encode --scheduler``): the caller's client, one to a scheduler's address, or a local
cluster started and stopped with the work, Dask's loggers held quiet meanwhile."""

import logging
import os
from contextlib import contextmanager

from mzc.errors import MzcError, first_line

CONNECT_SECONDS = 10   # to reach a scheduler given by --scheduler
DASK_LOGGERS = ("distributed", "distributed.client", "tornado", "tornado.application", "asyncio")
# Dask's nannies set MALLOC_TRIM_THRESHOLD_ in their workers' environment (None unsets it). That turns
# off glibc's adaptive mmap threshold, so every array above 128 KB is mapped and unmapped afresh:
# slicing and encoding a face then took 2.0x as long (0.76 s against 0.40 s a face, most of it in
# page faults: measured on the 13 faces, 2026-12-02). Workers of a scheduler need the same (README).
MALLOC_TRIM = "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"
# One task at a time per worker thread (Dask's default queues 1.1): when a worker dies, only the
# chunk it was running is charged with its death, so a bad file cannot take its neighbours along.
SATURATION = "distributed.scheduler.worker-saturation"
DASK_MISSING = "mzc batch runs on Dask, which is not installed: pip install 'mzc[batch]'"


@contextmanager
def dask_client(scheduler=None, workers=None):
    """A Dask client for the run: ``scheduler`` itself when it is a ``distributed.Client`` (the
    caller's, left open), a new one to the scheduler at the address ``scheduler``, else the
    caller's current client when there is one and no ``workers`` are asked for, else one to a
    local cluster of ``workers`` processes (one per core by default) started and stopped with it."""
    try:
        import dask
        from distributed import Client, LocalCluster
    except ImportError:
        raise MzcError(DASK_MISSING) from None
    if isinstance(scheduler, Client):
        yield scheduler
        return
    if scheduler is None and workers is None and (current := current_client(Client)) is not None:
        yield current
        return
    if scheduler is not None and not isinstance(scheduler, str):
        raise MzcError(f"must be a scheduler's address or a distributed.Client, not a {type(scheduler).__name__}",
                       field="scheduler")
    with quiet_logs():
        if scheduler is not None:
            try:
                client = Client(scheduler, timeout=CONNECT_SECONDS)
            except (OSError, TimeoutError, ValueError) as error:
                raise MzcError(f"cannot reach the Dask scheduler: {error}", source=scheduler) from None
            with client:
                yield client
            return
        with dask.config.set({MALLOC_TRIM: None, SATURATION: 1.0}):
            try:
                cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                                       processes=True, dashboard_address=None, silence_logs=logging.CRITICAL)
            except (RuntimeError, OSError, TimeoutError) as error:   # a worker process that died as it started
                raise MzcError(f"the local Dask cluster did not start: {first_line(error)}") from None
            with cluster, Client(cluster) as client:
                yield client


def current_client(client_type):
    """The caller's current Dask client (``with Client(...)``, or the last one made), or None."""
    try:
        return client_type.current()
    except ValueError:
        return None


@contextmanager
def quiet_logs():
    """Dask's and its event loop's loggers held to CRITICAL while mzc runs its own client or
    cluster (a worker's restart is not the user's news), then set back as they were: a host
    program's logging is its own."""
    loggers = [logging.getLogger(name) for name in DASK_LOGGERS]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels):
            logger.setLevel(level)
