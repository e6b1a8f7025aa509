"""mzc batch: items and layout, the manifest, one item's work, and whole runs on real Dask
processes (a scheduler and two workers on 127.0.0.1) with a worker and then the client
killed mid-run."""

import csv
import hashlib
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mzc
from mzc.api import sliceable_extensions
from mzc.batch import Job, items, manifest, work
from mzc.errors import MzcError
from mzc.meshes import mesh_to_bytes, read_mesh

from conftest import FACES, face_path, run_mzc

pytest.importorskip("distributed")

RMSE = {"rmse": 0.05}
ENCODE = {"codec": "dwt2d", "codec_options": {"rmse": 0.05, "wavelet": "bior4.4"}, "slice_options": {}}


def face_files():
    """The 13 shared faces (12 PLY, one OBJ), or a skip."""
    faces = sorted(FACES.glob("*.ply")) + [FACES / "example.obj"] if FACES.is_dir() else []
    if len(faces) < 13:
        pytest.skip("shared face data not available")
    return faces


def archive(folder, faces, bad=True):
    """A folder of the faces (linked), in two subfolders, plus a cut PLY and an empty file."""
    for index, face in enumerate(faces):
        target = folder / ("left" if index % 2 else "right") / face.name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.symlink_to(face)
    if bad:
        (folder / "cut.ply").write_bytes(faces[0].read_bytes()[:5000])
        (folder / "empty.ply").write_bytes(b"")
    return folder


def rows_of(dest):
    """The manifest's rows, output -> row."""
    return manifest.read(manifest.path_in(str(dest)))


def expected_bytes(face, **options):
    """What ``mzc slice FACE | mzc encode --dwt2d ...`` writes, computed in process."""
    return mzc.encode(mzc.slice(read_mesh(face)), "dwt2d", **options)


# --------------------------------------------------------------------------- items


def test_a_folder_is_walked_with_its_layout_leaving_out_hidden_names_and_the_destination(tmp_path):
    for name in ("a.ply", "sub/b.obj", "sub/deeper/c.stl", ".hidden/d.ply", "sub/.e.ply", "notes.md",
                 "out/old.ply"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("x")
    found = items.collect([str(tmp_path)], [".ply", ".obj", ".stl"], ".mzw2", str(tmp_path / "out"))
    assert [(Path(i.source).relative_to(tmp_path).as_posix(), i.output) for i in found] == [
        ("a.ply", "a.mzw2"), ("sub/b.obj", "sub/b.mzw2"), ("sub/deeper/c.stl", "sub/deeper/c.mzw2")]


def test_globs_keep_the_layout_below_their_fixed_part_and_files_keep_their_name(tmp_path):
    for name in ("2026/01/a.ply", "2026/02/b.ply", "2026/02/c.obj"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("x")
    found = items.collect([str(tmp_path / "2026" / "*" / "*.ply"), str(tmp_path / "2026/02/c.obj")], [".ply"],
                          ".mzw2", str(tmp_path / "out"))
    assert [i.output for i in found] == ["01/a.mzw2", "02/b.mzw2", "c.mzw2"]


def test_a_list_of_paths_skips_comments_and_takes_relative_paths_from_its_folder(tmp_path):
    for name in ("scans/x/a.ply", "scans/y/b.ply"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("x")
    listing = tmp_path / "todo.txt"
    listing.write_text(f"# today\nscans/x/a.ply\n\n{tmp_path / 'scans/y/b.ply'}\n")
    found = items.collect([f"@{listing}"], [".ply"], ".mzw2", str(tmp_path / "out"))
    assert [i.output for i in found] == ["x/a.mzw2", "y/b.mzw2"]
    listing.write_text("scans/x/a.ply\nscans/nope.ply\n")
    with pytest.raises(MzcError, match=r"todo.txt:2: no such file"):
        items.collect([f"@{listing}"], [".ply"], ".mzw2", str(tmp_path / "out"))


@pytest.mark.parametrize("sources, problem", [
    (["missing.ply"], "missing.ply: no such file or folder"),
    (["empty"], "no input found here"),
    (["*.nothing"], "no input found here"),
    (["a/f.ply", "b/f.ply"], "would both write f.mzw2"),
])
def test_sources_that_name_nothing_or_collide_are_refused_before_any_work(tmp_path, monkeypatch, sources, problem):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "empty").mkdir()
    for name in ("a/f.ply", "b/f.ply"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text("x")
    with pytest.raises(MzcError, match=problem):
        items.collect(sources, [".ply"], ".mzw2", str(tmp_path / "out"))


# --------------------------------------------------------------------------- manifest

# any character: line breaks, backslashes, and the surrogates by which Python holds the bytes
# of a file name that is not UTF-8 (and other lone surrogates)
text = st.text(st.characters() | st.characters(min_codepoint=0xD800, max_codepoint=0xDFFF, categories=["Cs"]),
               max_size=40)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.fixed_dictionaries({name: text for name in manifest.COLUMNS}), max_size=8,
                unique_by=lambda row: row["output"]))
def test_the_manifest_reads_back_what_it_wrote(rows):
    with_cells = [{name: manifest.cell(name, value) for name, value in row.items()} for row in rows]
    path = Path(os.environ.get("TMPDIR", "/tmp")) / f"mzc-manifest-{os.getpid()}.csv"
    try:
        path.write_text(manifest.text_of(rows), encoding="utf-8")
        assert manifest.read(str(path)) == {row["output"]: row for row in with_cells}
    finally:
        path.unlink(missing_ok=True)


def test_a_row_cut_by_a_kill_is_dropped_and_appending_starts_on_a_new_line(tmp_path):
    path = str(tmp_path / manifest.NAME)
    whole = {"input": "/a.ply", "output": "a.mzw2", "status": "ok", "seconds": 0.25}
    cut = manifest.line_of({"input": "/b.ply", "output": "b.mzw2", "status": "ok"})[:-9]
    Path(path).write_text(manifest.text_of([whole]) + cut, encoding="utf-8")
    assert list(manifest.read(path)) == ["a.mzw2"]
    appender = manifest.Appender(path)
    appender.append([{"input": "/c.ply", "output": "c.mzw2", "status": "failed", "error": 'bad, "quoted"'}])
    appender.close()
    rows = manifest.read(path)
    assert list(rows) == ["a.mzw2", "c.mzw2"] and rows["c.mzw2"]["error"] == 'bad, "quoted"'
    assert rows["a.mzw2"]["seconds"] == "0.250"


def test_a_file_that_is_not_a_manifest_is_not_overwritten(tmp_path):
    (tmp_path / manifest.NAME).write_text("name,size\nmine,1\n")
    with pytest.raises(MzcError, match="not an mzc batch manifest"):
        manifest.read(str(tmp_path / manifest.NAME))


# --------------------------------------------------------------------------- one item


def test_an_item_gives_the_bytes_of_slice_then_encode_and_the_errors_at_the_nodes(tmp_path, f18):
    job = Job("encode", str(tmp_path), ENCODE)
    row = work.run_item(job, items.Item(str(f18), "f18.mzw2"))
    data = (tmp_path / "f18.mzw2").read_bytes()
    assert row["status"] == "ok" and data == expected_bytes(f18, **RMSE)
    assert row["input_sha256"] == hashlib.sha256(f18.read_bytes()).hexdigest()
    assert (row["input_bytes"], row["output_bytes"]) == (f18.stat().st_size, len(data))
    decoded = mzc.decode(data)
    grid = mzc.slice(read_mesh(f18))
    error = abs(decoded.z - grid.z)[grid.valid]
    assert row["node_max_error"] == error.max() and row["valid_nodes"] == grid.valid.sum()
    assert (row["rows"], row["cols"]) == grid.shape
    assert set(row["timings"].split()[::2]) == {"read", "slice", "encode", "write"}


PUBLIC = Path(__file__).resolve().parent / "data" / "public"


@pytest.mark.parametrize("name", ["west_bijou_escarpment_snippet.asc", "srtm_blurred_res.tif"])
def test_a_raster_is_encoded_as_its_own_grid_with_its_georeferencing(tmp_path, name):
    if name.endswith(".tif"):
        pytest.importorskip("rasterio")
    folder = tmp_path / "in"
    folder.mkdir()
    for path in PUBLIC.glob(Path(name).stem + ".*"):   # the raster, and an ESRI grid's .prj
        (folder / path.name).symlink_to(path)
    source = folder / name
    taken = items.collect([str(folder)], sliceable_extensions(), ".mzw2", str(tmp_path / "out"))
    assert [item.source for item in taken] == [str(source)]   # a folder's raster is the job's file
    job = Job("encode", str(tmp_path), {**ENCODE, "codec_options": {"max_error": 0.01, "wavelet": "bior4.4"}},
              verify=True)
    row = work.run_item(job, items.Item(str(source), "dem.mzw2"))
    data = (tmp_path / "dem.mzw2").read_bytes()
    raster = mzc.slice(source)
    assert row["status"] == "ok" and data == mzc.encode(raster, "dwt2d", max_error=0.01)
    decoded = mzc.decode(data)
    assert (decoded.raster, decoded.crs, row["valid_nodes"]) == (raster.raster, raster.crs, raster.valid.sum())
    # an ESRI grid of whole metres is a raster of integers, exact at a bound under 1 (spec/dwt2d.md, Rounding)
    exact = raster.raster.sample.startswith(("int", "uint"))
    assert (row["node_max_error"] == 0) == exact and row["node_max_error"] <= 0.01
    assert row["surface_hausdorff"] <= row["node_max_error"] * (1 + 1e-9) + (1e-9 if exact else 0)
    cut = work.run_item(Job("encode", str(tmp_path), {**ENCODE, "slice_options": {"d1": 2.0}}),
                        items.Item(str(source), "cut.mzw2"))
    assert cut["status"] == "failed" and "resample the raster first" in cut["error"] and "d1" in cut["error"]


@pytest.mark.parametrize("file_format", ["tif", "asc"])
def test_a_raster_decodes_to_the_files_mzc_decode_writes(tmp_path, file_format):
    if file_format == "tif":
        pytest.importorskip("rasterio")
    archive = tmp_path / "archive"
    archive.mkdir()
    (archive / "west.mzw2").write_bytes(mzc.encode(mzc.slice(PUBLIC / "west_bijou_escarpment_snippet.asc"),
                                                   max_error=0.01))
    (archive / "blob.mzw2").write_bytes(mzc.encode(mzc.slice(mzc.sample("blob")), max_error=0.1))   # spherical
    job = Job("decode", str(tmp_path / "out"), {"densify": 1, "method": "biharmonic", "format": file_format,
                                                "jump_angle": None})
    west = work.run_item(job, items.Item(str(archive / "west.mzw2"), f"west.{file_format}"))
    blob = work.run_item(job, items.Item(str(archive / "blob.mzw2"), f"blob.{file_format}"))
    want = tmp_path / "want"
    want.mkdir()
    mzc.write(want / f"west.{file_format}", mzc.densify(mzc.read(archive / "west.mzw2"), 1))
    made = sorted(path.name for path in want.iterdir())
    assert made == (["west.asc", "west.prj"] if file_format == "asc" else ["west.tif"])
    for name in made:
        assert (tmp_path / "out" / name).read_bytes() == (want / name).read_bytes()
    assert west["status"] == "ok" and west["output_bytes"] == (want / f"west.{file_format}").stat().st_size
    assert blob["status"] == "failed" and "a raster holds planar grids" in blob["error"]
    assert sorted(path.name for path in (tmp_path / "out").iterdir()) == made


def test_a_rerun_keeps_an_item_only_while_its_input_settings_and_output_hold(tmp_path):
    source = tmp_path / "bump.obj"
    source.write_bytes(mesh_to_bytes(mzc.sample("bump"), "obj"))
    item = items.Item(str(source), "bump.mzw2")
    job = Job("encode", str(tmp_path), ENCODE)
    first = work.run_item(job, item)
    previous = {name: manifest.cell(name, value) for name, value in first.items()}
    assert work.run_item(job, item, previous).get("skipped")
    assert not work.run_item(Job("encode", str(tmp_path), {**ENCODE, "codec": "dct"}), item, previous).get("skipped")
    (tmp_path / "bump.mzw2").write_bytes(b"cut")
    assert not work.run_item(job, item, previous).get("skipped")
    source.write_bytes(source.read_bytes() + b"# changed\n")
    assert not work.run_item(job, item, previous).get("skipped")


def test_bad_items_become_failed_rows_with_their_one_line_error(tmp_path):
    (tmp_path / "empty.ply").write_bytes(b"")
    (tmp_path / "words.obj").write_text("v 1 2 three\n")
    job = Job("encode", str(tmp_path / "out"), ENCODE)
    rows = work.run_chunk(job, [(items.Item(str(tmp_path / n), n + ".mzw2"), None)
                                for n in ("empty.ply", "words.obj", "gone.ply")])
    assert [r["status"] for r in rows] == ["failed"] * 3
    assert "empty input" in rows[0]["error"] and "words.obj:1" in rows[1]["error"]
    assert "gone.ply: no such file" in rows[2]["error"]
    assert all("\n" not in r["error"] for r in rows) and not (tmp_path / "out").exists()


# --------------------------------------------------------------------------- whole runs


def test_a_local_cluster_encodes_and_decodes_an_archive(tmp_path):
    source = tmp_path / "in"
    source.mkdir()
    for name in ("bump", "tube"):
        (source / f"{name}.obj").write_bytes(mesh_to_bytes(mzc.sample(name), "obj"))
    summary = mzc.batch_encode(source, tmp_path / "coded", max_error=0.01, workers=2)
    assert not summary.failed and len(summary.rows) == 2
    assert summary.line().endswith("0 skipped, 0 failed")
    damaged = bytearray((tmp_path / "coded" / "bump.mzw2").read_bytes())
    damaged[-5] ^= 1
    (tmp_path / "coded" / "damaged.mzw2").write_bytes(damaged)
    meshes = mzc.batch_decode(tmp_path / "coded", tmp_path / "meshes", densify=1, file_format="obj", workers=2)
    assert [row["output"] for row in meshes.failed] == ["damaged.obj"] and "crc32" in meshes.failed[0]["error"]
    assert not (tmp_path / "meshes" / "damaged.obj").exists()
    for name in ("bump", "tube"):
        data = (tmp_path / "coded" / f"{name}.mzw2").read_bytes()
        assert data == mzc.encode(mzc.slice(source / f"{name}.obj"), "dwt2d", max_error=0.01)
        rebuilt = mzc.triangulate(mzc.densify(mzc.decode(data), 1))
        assert (tmp_path / "meshes" / f"{name}.obj").read_bytes() == mesh_to_bytes(rebuilt, "obj")


def test_a_callers_client_is_used_as_it_is_and_its_logging_left_alone(tmp_path):
    """A distributed.Client given as the scheduler, or the caller's current one, runs the batch;
    mzc neither closes it nor changes the levels of the host's loggers."""
    import logging

    from distributed import Client, LocalCluster, get_task_stream

    source = tmp_path / "in"
    source.mkdir()
    (source / "bump.obj").write_bytes(mesh_to_bytes(mzc.sample("bump"), "obj"))
    logging.getLogger("distributed").setLevel(logging.INFO)
    try:
        with LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster, Client(cluster) as client:
            with get_task_stream(client) as given_tasks:
                given = mzc.batch_encode(source, tmp_path / "given", scheduler=client, max_error=0.01)
            with get_task_stream(client) as current_tasks:
                current = mzc.batch_encode(source, tmp_path / "current", max_error=0.01)   # the current client
            assert given_tasks.data and current_tasks.data   # both ran on this cluster, not one of their own
            assert client.status == "running"
        assert logging.getLogger("distributed").level == logging.INFO
    finally:
        logging.getLogger("distributed").setLevel(logging.NOTSET)
    assert not given.failed and not current.failed
    expected = mzc.encode(mzc.slice(source / "bump.obj"), max_error=0.01)
    assert (tmp_path / "given" / "bump.mzw2").read_bytes() == expected
    assert (tmp_path / "current" / "bump.mzw2").read_bytes() == expected
    with pytest.raises(MzcError, match="scheduler"):
        mzc.batch_encode(source, tmp_path / "bad", scheduler=42, max_error=0.01)


def crash_on_poison(job, chunk):
    """run_chunk, except that a worker process dies outright on an item named ``poison``."""
    if any(item.output.startswith("poison") for item, _ in chunk):
        os._exit(1)
    return [{"output": item.output, "status": "ok"} for item, _ in chunk]


def test_a_chunk_that_kills_its_workers_is_split_and_only_the_culprit_fails(tmp_path):
    import cloudpickle
    import dask
    from distributed import Client, LocalCluster

    from mzc.batch.engine import finished_chunks
    from mzc.cluster import SATURATION

    cloudpickle.register_pickle_by_value(sys.modules[__name__])   # the workers cannot import this module
    job = Job("encode", str(tmp_path), ENCODE)
    chunks = [[(items.Item(f"/in/{name}", name), None) for name in names]
              for names in (["a", "poison", "b"], ["c", "d"])]
    with dask.config.set({"distributed.scheduler.allowed-failures": 0, SATURATION: 1.0}), \
            LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None, silence_logs=50) as cluster, \
            Client(cluster) as client:
        rows = [row for chunk in finished_chunks(client, job, chunks, task=crash_on_poison) for row in chunk]
    outcome = {row["output"]: row["status"] for row in rows}
    assert outcome == {"a": "ok", "b": "ok", "c": "ok", "d": "ok", "poison": "failed"}
    assert "a worker died each time it ran this file" in next(r["error"] for r in rows if r["output"] == "poison")


def free_port():
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.fixture(scope="module")
def scheduler():
    """A Dask scheduler and two workers (each a nanny and its worker process) on 127.0.0.1."""
    from distributed import Client

    address = f"tcp://127.0.0.1:{free_port()}"
    dask = [sys.executable, "-m", "dask"]
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    processes = [subprocess.Popen([*dask, "scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1],
                                   "--no-dashboard"], **quiet)]
    processes += [subprocess.Popen([*dask, "worker", address, "--nthreads", "1", "--no-dashboard",
                                    "--host", "127.0.0.1"], **quiet) for _ in range(2)]
    try:
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, processes[1:]
    finally:
        for process in processes:
            process.kill()
            process.wait()


def start_batch(source, dest, address):
    """``mzc batch encode SOURCE -o DEST --dwt2d --rmse 0.05`` on the scheduler, one item per task."""
    return subprocess.Popen([sys.executable, "-m", "mzc", "batch", "encode", str(source), "-o", str(dest), "--dwt2d",
                             "--rmse", "0.05", "--scheduler", address, "--chunk-size", "1"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def wait_for_rows(dest, count, process, timeout=120):
    """Wait until the manifest has ``count`` rows while ``process`` runs; fail if it ends first."""
    deadline = time.monotonic() + timeout
    path = Path(manifest.path_in(str(dest)))
    while time.monotonic() < deadline:
        assert process.poll() is None, "the batch ended before the test could interrupt it"
        if path.exists() and len(rows_of(dest)) >= count:
            return
        time.sleep(0.05)
    raise AssertionError(f"no {count} manifest rows within {timeout} s")


def worker_process(nanny):
    """The worker process a ``dask worker`` nanny started."""
    import psutil

    children = psutil.Process(nanny.pid).children(recursive=True)
    return next(c for c in children if "spawn_main" in " ".join(c.cmdline()))


def replaced(nanny, worker, timeout=60):
    """True once ``nanny`` runs a worker process other than ``worker``."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            if worker_process(nanny).pid != worker.pid:
                return True
        except StopIteration:
            pass
        time.sleep(0.1)
    return False


def test_a_worker_killed_mid_run_loses_nothing_and_bad_files_are_recorded(tmp_path, scheduler):
    address, nannies = scheduler
    faces = face_files()
    source = archive(tmp_path / "in", faces)
    batch = start_batch(source, tmp_path / "out", address)
    wait_for_rows(tmp_path / "out", 2, batch)
    victim = worker_process(nannies[0])
    victim.send_signal(signal.SIGKILL)
    _, stderr = batch.communicate(timeout=300)
    lines = stderr.decode().strip().splitlines()
    assert batch.returncode == 1 and lines[-1].endswith("2 failed"), stderr.decode()
    assert lines[-1].startswith("mzc batch encode: 15 items")
    assert len(lines) == 3 and all(line.startswith("mzc: ") for line in lines[:2]), lines   # no Dask noise
    rows = rows_of(tmp_path / "out")
    assert len(rows) == 15
    assert "truncated" in rows["cut.mzw2"]["error"] and "empty input" in rows["empty.mzw2"]["error"]
    assert {r["status"] for o, r in rows.items() if o not in ("cut.mzw2", "empty.mzw2")} == {"ok"}
    for face in faces:
        side = "left" if faces.index(face) % 2 else "right"
        written = (tmp_path / "out" / side / face.with_suffix(".mzw2").name).read_bytes()
        assert written == expected_bytes(face, **RMSE), face.name
    assert replaced(nannies[0], victim)
    pipeline = subprocess.run(f"{sys.executable} -m mzc slice {face_path('f18.ply')} | "
                              f"{sys.executable} -m mzc encode --dwt2d --rmse 0.05", shell=True, capture_output=True)
    assert pipeline.stdout == (tmp_path / "out" / "right" / "f18.mzw2").read_bytes()


def test_a_killed_client_resumes_without_redoing_the_done_items(tmp_path, scheduler):
    address, _ = scheduler
    source = archive(tmp_path / "in", face_files(), bad=False)
    dest = tmp_path / "out"
    batch = start_batch(source, dest, address)
    wait_for_rows(dest, 4, batch)
    batch.send_signal(signal.SIGKILL)
    batch.wait()
    done = rows_of(dest)
    assert 4 <= len(done) < 13
    stamps = {o: (dest / o).stat().st_mtime_ns for o in done}
    rerun = start_batch(source, dest, address)
    _, stderr = rerun.communicate(timeout=300)
    assert rerun.returncode == 0, stderr.decode()
    assert stderr.decode().strip().endswith(f"{len(done)} skipped, 0 failed")
    rows = rows_of(dest)
    assert len(rows) == 13 and {r["status"] for r in rows.values()} == {"ok"}
    assert {o: rows[o] for o in done} == done   # the done items' rows, seconds and all, as they were
    assert {o: (dest / o).stat().st_mtime_ns for o in done} == stamps   # and their files untouched
    with open(manifest.path_in(str(dest)), newline="") as file:
        assert len(list(csv.reader(file))) == 14   # one header, one row per item: nothing twice


def test_the_batch_command_reports_usage_and_missing_sources_in_one_line(tmp_path):
    usage = run_mzc("batch", "encode", str(tmp_path), "-o", str(tmp_path / "out"), "--dct", "--dwt2d")
    assert usage.returncode == 2 and "give exactly one codec" in usage.stderr.decode()
    missing = run_mzc("batch", "encode", str(tmp_path / "nope"), "-o", str(tmp_path / "out"), "--dwt2d", "--rmse", "1")
    assert missing.returncode == 1
    assert missing.stderr.decode() == f"mzc: {tmp_path / 'nope'}: no such file or folder\n"


def test_batch_help_does_not_start_or_import_dask(tmp_path):
    script = "import sys; from mzc.cli import main; sys.argv = ['mzc', 'batch', 'encode', '--help']\n" \
             "try:\n    main()\nexcept SystemExit:\n    pass\nprint('distributed' in sys.modules, file=sys.stderr)"
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert result.stderr.strip() == "False" and "SOURCES" in result.stdout


# --------------------------------------------------------------------------- one big raster: by windows


def float_dem(path, rows, cols, seed=7):
    """A ``rows`` x ``cols`` float32 GeoTIFF in UTM with a block of no-data cells, written by GDAL."""
    rasterio = pytest.importorskip("rasterio")
    from rasterio.transform import from_origin

    rng = np.random.default_rng(seed)
    r, c = np.mgrid[0:rows, 0:cols].astype(np.float32)
    z = 300 + 40 * np.sin(r / 37) * np.cos(c / 53) + rng.normal(0, 0.05, (rows, cols)).astype(np.float32)
    z[rows // 3:rows // 3 + 20, 10:60] = -9999
    with rasterio.open(path, "w", driver="GTiff", width=cols, height=rows, count=1, dtype="float32", crs="EPSG:32611",
                       transform=from_origin(440000, 3750000, 2, 2), nodata=-9999, tiled=True, blockxsize=256,
                       blockysize=256) as dataset:
        dataset.write(z, 1)
    return path


PEAK_SCRIPT = """
import sys, tracemalloc
import mzc
from mzc.batch import Job, items, work
from mzc.rasters.windows import GeoTiffSource
mzc.decode(mzc.encode(mzc.slice(mzc.sample("bump")), "dwt2d", max_error=0.05, tile=32))   # import the modules first
GeoTiffSource(sys.argv[1], "dem").close()
tracemalloc.start()
job = Job("encode", sys.argv[2], {"codec": "dwt2d", "codec_options": {"max_error": 0.05, "tile": int(sys.argv[3])},
                                  "slice_options": {}})
row = work.run_item(job, items.Item(sys.argv[1], "dem.mzw2"))
assert row["status"] == "ok", row
print(tracemalloc.get_traced_memory()[1])
"""


def test_batch_encodes_one_big_raster_by_windows_in_bounded_memory(tmp_path):
    """A raster of 10 x 9 tiles is read window by window, never whole: the Python heap's peak
    (numpy's arrays included; tracemalloc in a fresh process) stays well under its float64 grid,
    where reading it whole peaked at 7.6 times the grid (80.7 MB for a 1500 x 1400 raster, whose
    windows peaked at 6.0 MB; this one at 4.7 MB); the file decodes within the bound, and a rerun skips it."""
    rows, cols, tile = 1200, 1100, 128
    source = float_dem(tmp_path / "dem.tif", rows, cols)
    dest = tmp_path / "out"
    result = subprocess.run([sys.executable, "-c", PEAK_SCRIPT, str(source), str(dest), str(tile)],
                            capture_output=True, text=True, check=True)
    peak, grid_bytes = int(result.stdout.split()[-1]), rows * cols * 8
    assert peak < 0.6 * grid_bytes, (peak, grid_bytes)
    coded = (dest / "dem.mzw2").read_bytes()
    assert coded.startswith(b"mzc-dwt2d 5.0\n") and b"\ntiles 10 9\n" in coded
    original, back = mzc.read(source), mzc.decode(coded)
    assert np.array_equal(back.valid, original.valid) and np.nanmax(np.abs(back.z - original.z)) <= 0.05
    job = Job("encode", str(dest), {"codec": "dwt2d", "codec_options": {"max_error": 0.05, "tile": tile},
                                    "slice_options": {}})
    row = {"input": str(source), "output": "dem.mzw2", "settings": job.settings_text, "status": "ok",
           "input_sha256": hashlib.sha256(source.read_bytes()).hexdigest(), "output_bytes": len(coded)}
    assert work.run_item(job, items.Item(str(source), "dem.mzw2"), previous=row).get("skipped")


def test_a_raster_coded_by_windows_writes_over_only_its_own_file(tmp_path):
    source = float_dem(tmp_path / "dem.tif", 200, 180)
    job = Job("encode", str(tmp_path / "out"), {"codec": "dwt2d", "codec_options": {"max_error": 0.05, "tile": 64},
                                                "slice_options": {}})
    item = items.Item(str(source), "dem.mzw2")
    first = work.run_item(job, item)
    coded = (tmp_path / "out" / "dem.mzw2").read_bytes()
    assert first["status"] == "ok" and (first["rows"], first["cols"], first["output_bytes"]) == (200, 180, len(coded))
    assert coded == mzc.encode(mzc.read(source), "dwt2d", max_error=0.05, tile=64)
    assert work.run_item(job, item)["status"] == "ok"   # the same bytes there: nothing to write
    (tmp_path / "out" / "dem.mzw2").write_bytes(b"someone else's")
    refused = work.run_item(job, item)
    assert refused["status"] == "failed" and "was not written by this batch" in refused["error"]
    assert (tmp_path / "out" / "dem.mzw2").read_bytes() == b"someone else's"
    assert work.run_item(job, item, previous=first)["status"] == "ok"   # its own file: written again
    assert (tmp_path / "out" / "dem.mzw2").read_bytes() == coded


def test_batch_codes_the_tiles_of_one_big_raster_as_dask_tasks(tmp_path):
    """On a cluster the item's tiles are tasks of their own (the task stream shows the tile coder),
    spread over its workers, and the file is the same bytes as coded in one process."""
    from distributed import Client, LocalCluster, get_task_stream

    source = tmp_path / "in"
    source.mkdir()
    float_dem(source / "dem.tif", 200, 180)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None,
                      silence_logs=50) as cluster, Client(cluster) as client, get_task_stream(client) as stream:
        summary = mzc.batch_encode(source, tmp_path / "coded", scheduler=client, max_error=0.05, tile=64)
    assert not summary.failed
    names = [task["key"] if isinstance(task["key"], str) else task["key"][0] for task in stream.data]
    assert sum("coded_remotely" in name for name in names) == 4 * 3
    coded = (tmp_path / "coded" / "dem.mzw2").read_bytes()
    assert coded == mzc.encode(mzc.read(source / "dem.tif"), "dwt2d", max_error=0.05, tile=64)
