"""Running a batch on Dask: chunks of items as tasks, faults, resuming, the summary, and one
run at a time in a destination folder.

By default a local cluster is started for the run, one worker process per core with one
thread each (the work is numpy's and holds the GIL between calls); ``scheduler`` sends the
tasks to a running Dask scheduler instead, whose workers must see the same paths. Items go
in chunks of several (``chunk_size``; by default about 32 chunks per worker, so that a
worker's queue stays full and the last chunks even out), each chunk one task.

Faults: an item that fails is a failed row and the batch goes on. A worker that dies has
its chunks run again elsewhere by the scheduler (a local cluster's nanny restarts it); a
chunk that killed workers the scheduler's allowed number of times is split into single
items, and an item that still kills a worker becomes a failed row. A cluster left without
any worker for LOST_SECONDS, or whose scheduler went away, ends the run with an MzcError:
nothing would finish. Each finished chunk's rows are appended to the manifest before the
next is waited for, and a rerun skips the items whose rows still hold, so a batch killed
at any moment resumes where it stopped.
"""

from __future__ import annotations

import fcntl
import math
import os
import sys
import time
import uuid
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field

from mzc.batch import manifest
from mzc.batch.work import failed_row, run_chunk
from mzc.cluster import dask_client
from mzc.errors import MzcError, first_line

CHUNKS_PER_WORKER = 32
LOCK_NAME = ".manifest.lock"   # in DEST, while a run holds it
LOST_SECONDS = 10   # without a worker this long, a cluster has lost them for good (a restart takes 1-3 s)
POLL_SECONDS = 0.1   # how often a run waiting for its tasks looks at the cluster
MAX_CHUNK = 64
RESUME = "the manifest keeps the items done; run again to resume"


@dataclass
class Summary:
    """What a batch did: one row per item (done now, or ``skipped`` as done before), and time."""

    action: str
    rows: list[dict] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def failed(self) -> list[dict]:
        return [row for row in self.rows if row.get("status") != "ok"]

    @property
    def skipped(self) -> int:
        return sum(1 for row in self.rows if row.get("skipped"))

    def total(self, column: str) -> int:
        """The sum of a byte column over the items that are done."""
        return sum(int(row.get(column) or 0) for row in self.rows if row.get("status") == "ok")

    def line(self) -> str:
        """The one-line summary: items, bytes in and out of those done (or that none is), ratio,
        rate, skipped and failed items."""
        done_in, done_out = self.total("input_bytes"), self.total("output_bytes")
        ratio = f" ({done_in / done_out:.0f}x smaller)" if done_out and self.action == "encode" else ""
        sizes = (f"{human_bytes(done_in)} in, {human_bytes(done_out)} out{ratio}"
                 if len(self.failed) < len(self.rows) else "none done")
        rate = len(self.rows) / self.seconds if self.seconds > 0 else 0.0
        return (f"mzc batch {self.action}: {len(self.rows)} items, {sizes}, {rate:.2f} items/s in "
                f"{self.seconds:.1f} s; {self.skipped} skipped, {len(self.failed)} failed")


def human_bytes(count):
    """``1234567`` as ``1.2 MB``."""
    for unit in ("B", "KB", "MB", "GB", "TB"):
        if count < 1000 or unit == "TB":
            return f"{count:.0f} {unit}" if unit == "B" else f"{count:.1f} {unit}"
        count /= 1000


def run_batch(job, items, scheduler=None, workers=None, chunk_size=None, listener=None):
    """Do ``job`` to every item on Dask and return the Summary; the manifest in ``job.dest`` holds
    the rows. ``listener`` (a Listener) is told of the start and of each row as it comes.
    ``job.dest`` is held by this run alone (``locked``), and a run that cannot start leaves
    nothing there."""
    started = time.perf_counter()
    listener = listener or Listener()
    if os.path.exists(job.dest) and not os.path.isdir(job.dest):
        raise MzcError("the destination is not a folder", source=job.dest)
    path = manifest.path_in(job.dest)
    summary = Summary(job.action)
    with locked(job.dest):
        previous = manifest.read(path)
        with dask_client(scheduler, workers) as client:
            appender = manifest.Appender(path)
            listener.started(len(items))
            try:
                for rows in item_rows(client, job, items, previous, chunk_size):
                    appender.append([row for row in rows if not row.get("skipped")])
                    summary.rows += rows
                    for row in rows:
                        listener.row(row)
            finally:
                appender.close()
        # a run that stops early leaves the rows appended so far, which a rerun reads as they are
        done = {row["output"]: {k: v for k, v in row.items() if k != "skipped"} for row in summary.rows}
        manifest.rewrite(path, list({**previous, **done}.values()))
    summary.seconds = time.perf_counter() - started
    return summary


@contextmanager
def locked(folder):
    """Hold ``folder`` (made if need be) for this run alone: a second batch into it at the same
    time is refused in one line, where its outputs and rows would mix with ours. The lock is an
    flock on LOCK_NAME in the folder, which the system releases when the run ends in any way
    (SIGKILL too); the file is removed, and so is a folder the run made and left empty."""
    made = not os.path.isdir(folder)
    make_folder(folder)
    path = os.path.join(folder, LOCK_NAME)
    fd = lock_file(path, folder)
    try:
        yield
    finally:
        with suppress(OSError):   # while still locked: a batch that opened it sees it gone and takes a new one
            os.unlink(path)
        os.close(fd)
        if made:
            with suppress(OSError):   # not empty: the run wrote something
                os.rmdir(folder)


def lock_file(path, folder):
    """A descriptor of the file ``path`` (made if need be) that holds its exclusive flock, or an
    MzcError naming ``folder`` when another process holds it."""
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        except OSError as error:
            raise MzcError(f"cannot lock the destination folder: {error.strerror or error}", source=folder) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as error:
            os.close(fd)
            if isinstance(error, BlockingIOError):
                raise MzcError("another mzc batch is writing into this folder: wait for it to end, or give another "
                               "-o", source=folder) from None
            raise MzcError(f"cannot lock the destination folder: {error.strerror or error}", source=folder) from None
        if still_named(fd, path):
            return fd
        os.close(fd)   # the batch that held it removed it as it ended: lock the one there now


def still_named(fd, path):
    """True when the open file ``fd`` is the file named ``path``."""
    try:
        here = os.stat(path)
    except FileNotFoundError:
        return False
    mine = os.fstat(fd)
    return (here.st_dev, here.st_ino) == (mine.st_dev, mine.st_ino)


def make_folder(folder):
    """Make ``folder`` (and its parents) unless it is there, or an MzcError naming it."""
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as error:
        raise MzcError(f"cannot make the destination folder: {error.strerror or error}", source=folder) from None


def item_rows(client, job, items, previous, chunk_size=None):
    """The rows of ``items``, some at a time as they come: first those whose output is one of
    the batch's inputs (failed: never written), then each chunk's as its task finishes, the
    tasks given each item's row in ``previous`` (output -> row of an earlier run)."""
    clashing = outputs_over_inputs(job.dest, items)
    if clashing:
        yield [failed_row(job, item, f"{os.path.join(job.dest, item.output)}: is an input of this batch: give "
                                     "another -o") for item in items if item in clashing]
    tasks = [(item, previous.get(item.output)) for item in items if item not in clashing]
    size = chunk_size or default_chunk_size(len(tasks), worker_count(client))
    yield from finished_chunks(client, job, [tasks[i:i + size] for i in range(0, len(tasks), size)])


def outputs_over_inputs(dest, items):
    """The set of the items whose output, under ``dest``, is the file of one of the items' inputs
    (by any name)."""
    inputs = {file_id(item.source) for item in items} - {None}
    return {item for item in items if file_id(os.path.join(dest, item.output)) in inputs}


def file_id(path):
    """(device, inode) of the file at ``path`` (followed, if a link), None when there is none."""
    try:
        info = os.stat(path)
    except OSError:
        return None
    return info.st_dev, info.st_ino


def default_chunk_size(count, workers):
    """Items per task: about CHUNKS_PER_WORKER tasks per worker, at most MAX_CHUNK items each."""
    return max(1, min(MAX_CHUNK, math.ceil(count / (max(1, workers) * CHUNKS_PER_WORKER))))


def worker_count(client):
    """The workers the scheduler has now, or an MzcError when it cannot be reached."""
    try:
        return len(client.nthreads())
    except OSError as error:
        raise scheduler_lost(first_line(error)) from None


def scheduler_lost(reason):
    """The MzcError of a run whose scheduler went away, for ``reason``."""
    return MzcError(f"lost the Dask scheduler ({reason}): {RESUME}")


def finished_chunks(client, job, chunks, task=run_chunk):
    """The rows of each chunk, ``task(job, chunk)``, as its task finishes (in the order they
    finish). A chunk whose task kept killing workers is split into single items; an item that
    does is a failed row. An MzcError when the cluster can finish no more (``completed``)."""
    from distributed import as_completed
    from distributed.client import CancelledError
    from distributed.scheduler import KilledWorker

    run = uuid.uuid4().hex[:8]
    submitted = {}

    def submit(chunk, index):
        future = client.submit(task, job, chunk, pure=False, key=f"mzc-batch-{run}-{index}")
        submitted[future.key] = chunk
        return future

    # with the results, fetched as each task finishes: a result asked for later, once the worker
    # that held it has died, waits for its task to run again, on no worker if none is left
    pending = as_completed([submit(chunk, str(i)) for i, chunk in enumerate(chunks)], with_results=True,
                           raise_errors=False)
    for future, result in completed(client, pending, job.dest):
        chunk = submitted.pop(future.key)
        future.release()
        if isinstance(result, list):   # the rows (the future may be 'lost' or 'cancelled' since)
            yield result
            continue
        error = result[1] if isinstance(result, tuple) else result   # (type, error, traceback), or CancelledError
        if isinstance(error, CancelledError):
            raise scheduler_lost("it cancelled the run's tasks")
        if not isinstance(error, KilledWorker):
            raise error
        if len(chunk) > 1:
            for i, single in enumerate(chunk):
                pending.add(submit([single], f"{future.key}-{i}"))
        else:
            item, previous = chunk[0]
            yield [failed_row(job, item, f"{item.source}: a worker died each time it ran this file (out of memory, "
                                         "or a crash)", previous)]


def completed(client, pending, dest):
    """The (future, result) pairs of ``pending`` (a distributed.as_completed with results) as
    they finish, or an MzcError naming ``dest`` once the cluster has had no worker for
    LOST_SECONDS, when nothing would finish: a nanny starts a worker that died again, but
    gives up on one that dies as it starts, and a scheduler's workers may all be gone."""
    alone_since = None
    while not pending.is_empty():
        if pending.has_ready():
            yield next(pending)
            continue
        now = time.monotonic()
        alone_since = None if worker_count(client) else (alone_since or now)
        if alone_since is not None and now - alone_since > LOST_SECONDS:
            raise MzcError(f"the Dask cluster has had no worker for {LOST_SECONDS} s (they died and none came back): "
                           f"{RESUME}", source=dest)
        time.sleep(POLL_SECONDS)


class Listener:
    """What a run tells as it goes (nothing, here): ``started(count)`` once, then ``row(row)`` per item."""

    def started(self, count):
        pass

    def row(self, row):
        pass


class TerminalProgress(Listener):
    """A listener that prints each failed item's error on ``stream`` as it comes and, when
    ``bar`` is true (stderr is a terminal), keeps one updated line: items, bytes in and out,
    rate and ETA."""

    def __init__(self, stream=sys.stderr, bar=False):
        self.stream, self.bar = stream, bar
        self.count = self.done = self.bytes_in = self.bytes_out = 0
        self.started_at = time.perf_counter()

    def started(self, count):
        self.count = count
        self.started_at = time.perf_counter()
        self.draw()

    def row(self, row):
        self.done += 1
        if row.get("status") == "ok":
            self.bytes_in += int(row.get("input_bytes") or 0)
            self.bytes_out += int(row.get("output_bytes") or 0)
        else:
            self.clear()
            print(f"mzc: {row.get('error')}", file=self.stream, flush=True)
        self.draw()

    def draw(self):
        if not self.bar:
            return
        elapsed = time.perf_counter() - self.started_at
        rate = self.done / elapsed if elapsed > 0 else 0.0
        eta = (self.count - self.done) / rate if rate > 0 else float("nan")
        filled = int(20 * self.done / self.count) if self.count else 20
        eta_text = f"ETA {eta:.0f} s" if math.isfinite(eta) else "ETA ?"
        self.stream.write(f"\r[{'#' * filled}{'.' * (20 - filled)}] {self.done}/{self.count} items, "
                          f"{human_bytes(self.bytes_in)} in, {human_bytes(self.bytes_out)} out, {rate:.1f} items/s, "
                          f"{eta_text}\x1b[K")
        self.stream.flush()

    def clear(self):
        if self.bar:
            self.stream.write("\r\x1b[K")
            self.stream.flush()
