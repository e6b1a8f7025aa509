"""A hostile corpus for issue 29's batch and output cases: what an audit found when outputs are
inputs, workers die for good, names are not UTF-8, the disk fills up, two writers meet and
root writes. Each case is refused in one line naming the file and the reason (exit status 1
or 2, no traceback, no foreign warning), or done right, and none runs on for long.

Concurrent writers are made deterministic by holding the lock the code takes and watching
/proc/locks for the other process to wait on it, never by sleeping and hoping."""

import fcntl
import os
import subprocess
import sys
import time
from contextlib import contextmanager, suppress

import pytest

import mzc
from mzc.batch import manifest
from mzc.errors import MzcError
from mzc.meshes import mesh_to_bytes

from conftest import FACES, run_mzc
from test_cli import assert_one_line_error

pytest.importorskip("distributed")

GRID = b"mzc-zgrid 1.0\nrows 2\ncols 2\nd1 1\nd2 1\ndata\n1 2\n3 4\n"
ENCODE = ("--dwt2d", "--max-error", "0.01", "--workers", "1")


def until(condition, timeout=60):
    """Poll ``condition`` until it holds (True) or ``timeout`` seconds pass (False)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.02)
    return False


def waits_for_lock(pid, path):
    """True when process ``pid`` is blocked on a lock of ``path``'s file (a '->' line of /proc/locks)."""
    info = os.stat(path)
    inode = f"{os.major(info.st_dev):02x}:{os.minor(info.st_dev):02x}:{info.st_ino} "
    with open("/proc/locks") as locks:
        return any("->" in line and f" {pid} " in line and inode in line for line in locks)


@contextmanager
def started(*args, env=None):
    """``python -m mzc ARGS`` running (``env``: variables added to the environment), its output
    captured; killed if it still runs at the end."""
    process = subprocess.Popen([sys.executable, "-m", "mzc", *map(str, args)], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, env={**os.environ, **(env or {}), "MZC_DEBUG": ""})
    try:
        yield process
    finally:
        if process.poll() is None:
            process.kill()
        process.communicate()


def rows_of(dest):
    """The manifest's rows in ``dest``, output -> row."""
    return manifest.read(manifest.path_in(str(dest)))


def bump_folder(folder, names):
    """``folder`` made, with the bump sample as NAME.obj for each of ``names``."""
    folder.mkdir()
    data = mesh_to_bytes(mzc.sample("bump"), "obj")
    for name in names:
        (folder / f"{name}.obj").write_bytes(data)
    return folder


def esri_grids(folder, count):
    """``folder`` made, with ``count`` small ESRI ASCII grids (g00.asc, ...), each a moment's work."""
    folder.mkdir()
    for index in range(count):
        heights = "\n".join(" ".join(str((row * col + index) % 7) for col in range(16)) for row in range(16))
        (folder / f"g{index:02d}.asc").write_text("ncols 16\nnrows 16\nxllcorner 0\nyllcorner 0\ncellsize 1\n"
                                                  f"NODATA_value -9999\n{heights}\n")
    return folder


def fill(folder):
    """Fill the file system of ``folder`` to its last byte."""
    with open(folder / "filler", "wb", buffering=0) as filler:
        try:
            while True:
                filler.write(bytes(1 << 16))
        except OSError:
            pass


# a Dask preload that makes a worker process die as it starts while the file NO_WORKERS names exists
NO_WORKER = """
import os


def dask_setup(worker):
    if os.path.exists(os.environ["NO_WORKERS"]):
        os._exit(1)
"""


def no_worker_config(folder):
    """The environment variables of an mzc whose Dask workers die as they start once
    ``folder``/stop exists, and that path: the preload NO_WORKER in a Dask config in ``folder``."""
    folder.mkdir()
    (folder / "no_worker.py").write_text(NO_WORKER)
    (folder / "dask.yaml").write_text(f"distributed:\n  worker:\n    preload:\n      - {folder / 'no_worker.py'}\n")
    return {"DASK_CONFIG": str(folder), "NO_WORKERS": str(folder / "stop")}, folder / "stop"


# --------------------------------------------------------------------------- -o


def test_two_writers_of_a_hard_linked_file_take_turns(tmp_path):
    """A hard-linked output is written in place under an exclusive lock: while another writer
    holds the file (here the test, half way through its own longer content), mzc waits for it,
    then writes its whole file, which ends as mzc wrote it, not cut short nor with the other's
    tail (the audit: 1 in 6 such pairs left a file that failed its CRC, both exit 0)."""
    if not os.path.exists("/proc/locks"):
        pytest.skip("no /proc/locks to see a process wait on a lock")
    grid, target, twin = tmp_path / "g.zg", tmp_path / "out.mzd", tmp_path / "twin.mzd"
    grid.write_bytes(GRID)
    want = subprocess.run([sys.executable, "-m", "mzc", "encode", "--dct", "-q", "5", grid], capture_output=True,
                          check=True).stdout
    target.write_bytes(b"old")
    os.link(target, twin)
    with started("encode", "--dct", "-q", "5", grid, "-o", twin) as writer:
        with open(target, "r+b") as other:
            fcntl.flock(other, fcntl.LOCK_EX)
            assert until(lambda: writer.poll() is not None or waits_for_lock(writer.pid, target))
            assert writer.poll() is None, "mzc wrote the file while another writer held it"
            other.write(b"the other writer's longer content " * 100)
            other.flush()
        _, stderr = writer.communicate(timeout=60)
        assert writer.returncode == 0, stderr
    assert target.read_bytes() == twin.read_bytes() == want


# --------------------------------------------------------------------------- mzc batch


def test_a_batch_never_writes_over_a_file_it_did_not_write(tmp_path):
    """An output that is there and that no row of the manifest says the batch wrote, or that
    is one of the batch's inputs (here through a symlink), is a failed row saying so, and the
    file is kept (the audit: 'batch encode io -o io; batch decode io -o io' replaced the scan
    io/scan.ply by the decoded mesh, exit 0)."""
    io = tmp_path / "io"
    io.mkdir()
    scan = mesh_to_bytes(mzc.sample("bump"), "ply")
    (io / "scan.ply").write_bytes(scan)
    assert run_mzc("batch", "encode", io, "-o", io, *ENCODE).returncode == 0
    coded = (io / "scan.mzw2").read_bytes()
    decoded = run_mzc("batch", "decode", io, "-o", io, "--workers", "1")
    lines = decoded.stderr.decode().splitlines()
    assert decoded.returncode == 1 and lines[-1].endswith("0 skipped, 1 failed"), lines
    assert lines[-1].startswith("mzc batch decode: 1 items, none done, "), lines   # not "0 B in, 0 B out"
    assert lines[:-1] == [f"mzc: {io / 'scan.ply'}: is there already and was not written by this batch (no row of "
                          "its manifest says so): move it away or give another -o"]
    assert (io / "scan.ply").read_bytes() == scan and rows_of(io)["scan.ply"]["status"] == "failed"
    (io / "scan.ply").unlink()
    (io / "alias.mzw2").symlink_to("scan.mzw2")
    (io / "alias.ply").symlink_to("alias.mzw2")   # alias.mzw2's output: that input itself
    linked = run_mzc("batch", "decode", io / "alias.mzw2", "-o", io, "--workers", "1")
    assert linked.returncode == 1 and f"mzc: {io / 'alias.ply'}: is an input of this batch" in linked.stderr.decode()
    assert (io / "scan.mzw2").read_bytes() == coded


def test_a_batch_writes_over_its_own_outputs_unless_they_are_read_only(tmp_path):
    """A file there that the batch would write byte for byte (a worker died after writing it,
    before its row was recorded) is kept as it is and recorded; an output the manifest says the
    batch wrote is written again with new settings, unless it was made read-only (0444): that
    one is refused, for root too."""
    source, dest = bump_folder(tmp_path / "in", ["a", "b", "c"]), tmp_path / "out"
    assert run_mzc("batch", "encode", source, "-o", dest, *ENCODE).returncode == 0
    stamp = (dest / "c.mzw2").stat().st_mtime_ns
    (dest / manifest.NAME).write_text(manifest.text_of([row for output, row in rows_of(dest).items()
                                                        if output != "c.mzw2"]))
    resumed = run_mzc("batch", "encode", source, "-o", dest, *ENCODE)
    assert resumed.returncode == 0 and resumed.stderr.decode().endswith("2 skipped, 0 failed\n"), resumed.stderr
    assert rows_of(dest)["c.mzw2"]["status"] == "ok" and (dest / "c.mzw2").stat().st_mtime_ns == stamp
    coded = {output: (dest / output).read_bytes() for output in rows_of(dest)}
    (dest / "b.mzw2").chmod(0o444)
    again = run_mzc("batch", "encode", source, "-o", dest, "--dwt2d", "--max-error", "0.02", "--workers", "1")
    lines = again.stderr.decode().splitlines()
    assert again.returncode == 1 and lines[-1].endswith("0 skipped, 1 failed"), lines
    assert lines[:-1] == [f"mzc: {dest / 'b.mzw2'}: permission denied (the file is read-only)"]
    rows = rows_of(dest)
    assert [rows[o]["status"] for o in ("a.mzw2", "b.mzw2", "c.mzw2")] == ["ok", "failed", "ok"]
    assert [(dest / o).read_bytes() == coded[o] for o in ("a.mzw2", "b.mzw2", "c.mzw2")] == [False, True, False]


def test_a_cluster_that_loses_every_worker_for_good_ends_in_one_line(tmp_path):
    """Workers killed while none can start again (here each dies as it starts, as a nanny's
    restart can fail): the run ends with one line, exit status 1, within LOST_SECONDS of the
    last worker, the rows done kept (the audit: repeated SIGKILLs left mzc batch waiting
    forever with no workers). A cluster whose workers die as it starts is one line too."""
    import psutil

    from mzc.batch.engine import LOST_SECONDS

    env, stop = no_worker_config(tmp_path / "dask")
    source, dest = esri_grids(tmp_path / "in", 200), tmp_path / "out"
    command = ["batch", "encode", source, "-o", dest, *ENCODE, "--chunk-size", "1"]
    with started(*command, env=env) as batch:
        assert until(lambda: batch.poll() is not None or len(rows_of(dest)) >= 2)
        stop.touch()
        for child in psutil.Process(batch.pid).children(recursive=True):
            with suppress(psutil.Error):   # gone already
                if "spawn_main" in " ".join(child.cmdline()):
                    child.kill()
        _, stderr = batch.communicate(timeout=LOST_SECONDS + 60)
    assert batch.returncode == 1 and stderr.decode() == (
        f"mzc: {dest}: the Dask cluster has had no worker for {LOST_SECONDS} s (they died and none came back): the "
        "manifest keeps the items done; run again to resume\n")
    assert 2 <= len(rows_of(dest)) < 200
    assert_one_line_error(run_mzc(*command, env=env), "mzc: the local Dask cluster did not start: ")


def test_any_name_the_file_system_allows_is_recorded_and_read_back(tmp_path):
    """Names with bytes that are not UTF-8, CR, LF and backslashes are escaped in the manifest,
    one line of UTF-8 a row, and read back exactly: a rerun skips them all (the audit: a name
    that is not UTF-8 made every run an internal error with no rows, even for the good files;
    a CR was written unquoted and every later run failed to read the manifest)."""
    names = ["plain", "bad\udcff", "cr\r", "nl\n", "back\\slash"]
    source, dest = bump_folder(tmp_path / "in", names), tmp_path / "out"
    first = run_mzc("batch", "encode", source, "-o", dest, *ENCODE)
    assert first.returncode == 0 and first.stderr.decode().endswith("0 skipped, 0 failed\n"), first.stderr
    again = run_mzc("batch", "encode", source, "-o", dest, *ENCODE)
    assert again.returncode == 0 and again.stderr.decode().endswith("5 skipped, 0 failed\n"), again.stderr
    rows = manifest.read(manifest.path_in(str(dest)))
    assert {output: row["input"] for output, row in rows.items()} == {f"{n}.mzw2": str(source / f"{n}.obj")
                                                                      for n in names}
    assert all((dest / output).is_file() for output in rows)
    assert (dest / manifest.NAME).read_bytes().decode("utf-8").count("\n") == 1 + len(names)


def test_an_error_longer_than_csv_reads_is_cut_in_the_manifest(tmp_path):
    """A PLY whose element name is 200,000 characters long fails with that name in its error;
    the manifest keeps it cut to a length csv reads back, so the next run reads the manifest
    (the audit: a field over 128 KB made every later run an internal error)."""
    source, dest = tmp_path / "in", tmp_path / "out"
    source.mkdir()
    (source / "long.ply").write_text("ply\nformat ascii 1.0\nelement " + "y" * 200_000 + " 1\nend_header\n1\n")
    for _ in range(2):
        result = run_mzc("batch", "encode", source, "-o", dest, *ENCODE)
        lines = result.stderr.decode().splitlines()
        assert result.returncode == 1 and lines[-1].endswith("0 skipped, 1 failed"), lines[-1][-300:]
    error = manifest.read(manifest.path_in(str(dest)))["long.mzw2"]["error"]
    assert error.startswith(f"{source / 'long.ply'}: element yyy") and error.endswith(" characters)")
    assert len(error) <= manifest.MAX_CELL + 100


def test_a_manifest_csv_cannot_read_is_refused_in_one_line(tmp_path):
    """A manifest.csv that mzc did not write, with a field longer than csv reads, is refused
    naming it and the line, before any work."""
    path = tmp_path / manifest.NAME
    path.write_text(manifest.text_of([]) + "x" * 200_000 + "\n")
    with pytest.raises(MzcError, match=r"manifest.csv:2: cannot read the manifest \(field larger than"):
        manifest.read(str(path))
    result = run_mzc("batch", "encode", bump_folder(tmp_path / "in", ["a"]), "-o", tmp_path, *ENCODE)
    assert result.returncode == 1 and result.stderr.decode().count("\n") == 1
    assert "manifest.csv:2: cannot read the manifest" in result.stderr.decode()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in", manifest.NAME]


def test_a_full_disk_while_appending_the_manifest_ends_in_one_line_and_loses_no_row(tmp_path, small_disk):
    """When the disk fills up under a batch, each item that cannot be written is a failed row,
    and the manifest that cannot grow stops the run with one line naming it (the audit: an
    internal error). Every output keeps a row (its earlier one, or its failure) and its file;
    with space again, the rerun does them all."""
    source, dest = esri_grids(tmp_path / "in", 24), small_disk / "out"
    coarse = ("--dwt2d", "--max-error", "0.5", "--workers", "1")
    assert run_mzc("batch", "encode", source, "-o", dest, *coarse).returncode == 0
    before = rows_of(dest)
    files = {output: (dest / output).read_bytes() for output in before}
    fill(small_disk)
    full = run_mzc("batch", "encode", source, "-o", dest, *ENCODE)
    lines = full.stderr.decode().splitlines()
    assert full.returncode == 1, lines
    assert lines[-1] == f"mzc: {dest / manifest.NAME}: no space left on device"
    assert all(line.startswith("mzc: ") and line.endswith("no space left on device") for line in lines), lines
    after = rows_of(dest)
    assert after.keys() == before.keys()
    assert all(after[o] == before[o] or after[o]["error"].endswith("no space left on device") for o in after)
    assert {output: (dest / output).read_bytes() for output in before} == files
    (small_disk / "filler").unlink()
    again = run_mzc("batch", "encode", source, "-o", dest, *ENCODE)
    assert again.returncode == 0 and again.stderr.decode().endswith("0 skipped, 0 failed\n"), again.stderr
    assert len(rows_of(dest)) == 24 and sorted(os.listdir(dest)) == sorted([manifest.NAME, *before])


def test_a_second_batch_into_a_folder_in_use_is_refused(tmp_path):
    """A batch holds its destination: a second one started into it meanwhile is refused in one
    line before any work, and the first one's outputs and rows are all its own (the audit: two
    runs at once gave 24 outputs and 12 rows, both exit 0). The lock goes with the run."""
    faces = sorted(FACES.glob("*.ply")) if FACES.is_dir() else []
    if len(faces) < 12:
        pytest.skip("shared face data not available")
    source, dest = tmp_path / "in", tmp_path / "out"
    source.mkdir()
    for face in faces:
        (source / face.name).symlink_to(face)
    with started("batch", "encode", source, "-o", dest, "--dwt2d", "--rmse", "0.05", "--workers", "1") as first:
        assert until(lambda: first.poll() is not None or len(rows_of(dest)) >= 1)
        second = run_mzc("batch", "encode", source, "-o", dest, "--dwt2d", "--rmse", "0.1", "--workers", "1")
        assert first.poll() is None, "the first batch ended before the second one was tried"
        assert_one_line_error(second, f"{dest}: another mzc batch is writing into this folder")
        _, stderr = first.communicate(timeout=300)
        assert first.returncode == 0, stderr
    settings = {row["settings"] for row in rows_of(dest).values()}
    assert len(settings) == 1 and '"rmse":0.05' in settings.pop()
    assert sorted(os.listdir(dest)) == sorted([manifest.NAME, *(face.stem + ".mzw2" for face in faces)])
