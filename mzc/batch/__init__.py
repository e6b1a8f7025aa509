"""``mzc batch``: slice and encode (or decode and triangulate) whole archives on Dask.

The work is split in four modules, each with one job:

- ``items``: what to do: the sources (files, folders, globs, lists of paths) as items, each
  an input path and the output path it gets under the destination (the same layout);
- ``work``: doing it: one item in one process, with the same functions the filters call
  (``mzc slice | mzc encode`` in-process gives the same bytes), into one manifest row;
  imports no Dask, so a worker runs it as plain Python;
- ``manifest``: what was done: the CSV beside the outputs (one row per item), appended as
  results come and read back to resume a batch that was stopped;
- ``engine``: the run: chunks of items as Dask tasks on a local cluster or a scheduler,
  faults (a dead worker's chunks rerun, a chunk that kills workers split), progress and
  the summary.
"""

from mzc.batch.engine import Summary, run_batch
from mzc.batch.work import Job

__all__ = ["Job", "Summary", "run_batch"]
