"""Cuberille's work on a Dask cluster, with the same files as one machine.

    from distributed import Client, LocalCluster
    import cuberille.dask

    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        cuberille.dask.render(["model.glb", "--turntable", "36", "--out", "frames/f.png"], client)
        cuberille.dask.batch("jobs.jsonl", client)
        cuberille.dask.accuracy(["model.glb", "--out", "report"], client)
        cuberille.dask.fly(["model.cvox", "--frames", "600", "--out-dir", "flight", "--save-every", "1"], client)
        cuberille.dask.voxelize(["scan.cgs", "--resolution", "4096", "-o", "scan.cvox"], client)

`python3 -m cuberille.dask render|batch|accuracy|fly|voxelize ...` is the command line over these
(docs/scale-out.md).

How the work is split, and why the files are the same as the tool's:
- A command is read by the tool's own parser (cuberille._cuberille.RenderCommand, AccuracyCommand,
  FlyCommand, VoxelizeCommand), here and again on each worker, so it takes the same options and refuses bad ones with the same messages.
- A sequence (--turntable, --animate) is cut into contiguous runs of frames, one task each. A
  frame's image never depends on the frames before it (render/loaded_scene.h), only the work does:
  a run's first frame builds the hierarchies the later frames of the run refit.
- Each worker process loads a scene once and keeps it for every later task that names it with the
  same --detail and --up-axis (`_scene`).
- An accuracy sweep is planned here (the tool's probe render and sweep), each setting's renders —
  `cuberille render` processes, as the tool runs them — are a task, and the report is finished here
  from the rows the tasks send back (apps/accuracy_command.h: planAccuracy, runAccuracySetting,
  finishAccuracy), comparing each setting's image with the ground truth's as the tool does.
- A flight (`fly`) is cut into contiguous runs of its path's frames, one task each; a run is flown
  from a cold start (the model opened, nothing resident, no occlusion history: what that costs is
  in docs/scale-out.md), its frames numbered and saved as in the whole flight; the run that ends
  the path settles and writes final.png; the client joins the runs' statistics into the tool's
  CSV, plot and summary (apps/fly_command.h).
- A voxelization (`voxelize`) is cut into runs of the input's chunks (a .cgs: each worker reads
  only its chunks); each run's partial voxelization (every touched voxel's integer sums and its
  blocks' source triangles with their order keys) is written to a part file beside the output;
  then the model's blocks are cut into ranges of whole subtrees of the LOD pyramid, and each range
  is a task: its blocks merged from every part (integer sums: any split gives the single-machine
  blocks bit for bit) and its pyramid built up to the split level, into a range file; the client
  builds the few levels above and writes the .cvox, copying the rest from the range files
  (lod/pyramid_ranges.h, apps/voxel_commands.h): no process holds the finest level.
- Every file is written under a temporary name and renamed (apps/atomic_file.h), so a task retried
  after its worker died rewrites whole files; the temporary files a killed worker left are removed
  once every task has finished (`_remove_leftovers`). Outputs go where the command names them: the
  workers and this process must see the same file system.
"""

import glob
import json
import math
import os
import shutil
import sys
import time

from .. import Scene, _cuberille
from .._cuberille import InputError

__all__ = ["AccuracyReport", "BatchReport", "FlyReport", "RenderReport", "VoxelizeReport", "accuracy", "batch", "fly",
           "render", "voxelize"]


class RenderReport:
    """What render() did: the files written in frame order, each frame's statistics (the dicts
    --stats holds), the tasks and workers it used and its wall time."""

    def __init__(self, files, frame_stats, tasks, workers, seconds, warnings):
        self.files, self.frame_stats, self.tasks, self.workers = files, frame_stats, tasks, workers
        self.seconds, self.warnings = seconds, warnings


class BatchReport:
    """What batch() did: how many jobs ran, the failures as (line number, message) in line order,
    how many scene loads the workers made, and the wall time."""

    def __init__(self, jobs, failures, scene_loads, seconds, warnings):
        self.jobs, self.failures, self.scene_loads, self.seconds, self.warnings = jobs, failures, scene_loads, seconds, warnings


class AccuracyReport:
    """What accuracy() did: the report's folder, the rows it holds, the settings rendered as tasks
    (a command line several knobs share renders once), the workers and the wall time."""

    def __init__(self, folder, rows, tasks, workers, seconds):
        self.folder, self.rows, self.tasks, self.workers, self.seconds = folder, rows, tasks, workers, seconds


class FlyReport:
    """What fly() did: the images written (saved frames, then final.png), the frames flown (the
    path's and the last run's settling ones), what the runs read from disk together, the tasks,
    workers and wall time, and the blocks that could not be read."""

    def __init__(self, files, frames, bytes_read, tasks, workers, seconds, warnings):
        self.files, self.frames, self.bytes_read, self.tasks = files, frames, bytes_read, tasks
        self.workers, self.seconds, self.warnings = workers, seconds, warnings


class VoxelizeReport:
    """What voxelize() did: the model written, the input's chunks, the tasks voxelizing runs of
    them, the tasks merging ranges of blocks, the workers and the wall time."""

    def __init__(self, out, chunks, tasks, range_tasks, workers, seconds):
        self.out, self.chunks, self.tasks, self.range_tasks = out, chunks, tasks, range_tasks
        self.workers, self.seconds = workers, seconds


def render(arguments, client, *, frames_per_task=None, progress=None):
    """Runs `cuberille render ARGUMENTS` (the scene and options, as on the command line) on the
    client's cluster. Raises InputError as the tool refuses: a bad option before any task, a bad
    scene file from the first task that reads it (the other tasks are cancelled). `progress`, if
    given, is called with (frames done, frames in all) as runs finish."""
    started = time.perf_counter()
    arguments = [os.fspath(a) for a in arguments]
    command = _cuberille.RenderCommand.from_arguments(arguments)
    count = command.frame_count
    runs, results, workers = _frame_runs(client, _render_run, arguments, count, frames_per_task, progress, "render")
    files = [command.frame_file(i) for i in range(count)]
    _remove_leftovers(files)
    frame_stats = [s for first, _ in runs for s in results[first]["stats"]]
    if command.stats:
        command.write_stats(frame_stats)
        _remove_leftovers([command.stats])
    warnings = _unique(w for first, _ in runs for w in results[first]["warnings"])
    return RenderReport(files, [json.loads(s) for s in frame_stats], len(runs), workers,
                        time.perf_counter() - started, warnings)


def batch(jobs_path, client, *, jobs_per_task=None, progress=None):
    """Runs a `cuberille batch` jobs file on the client's cluster, in tasks of consecutive job lines
    (`jobs_per_task`; by default four tasks a worker, as render's runs). A job that fails is
    reported with its line number and the message the tool gives; the others go on. Raises
    InputError if the jobs file cannot be read. `progress`, if given, is called with (jobs done,
    jobs in all) as tasks finish."""
    started = time.perf_counter()
    jobs_path = os.fspath(jobs_path)
    try:
        with open(jobs_path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise InputError(f"{jobs_path}: cannot open file ({e.strerror})") from None
    numbered = [(n, line) for n, line in enumerate(lines, start=1)
                if line.strip(" \t\r") and not line.lstrip(" \t").startswith("#")]
    per_task = jobs_per_task or _items_per_task(len(numbered), _worker_count(client))
    groups = [numbered[i:i + per_task] for i in range(0, len(numbered), per_task)]
    threads = _threads_per_worker(client)
    futures = {client.submit(_batch_jobs, group, threads, pure=False, key=f"cuberille-jobs-{group[0][0]}-{_stamp()}"): group
               for group in groups}
    from distributed import as_completed

    failures, loads, warnings, done = [], 0, [], 0
    for future in as_completed(futures):
        group = futures[future]
        try:
            results = future.result()
        except Exception as e:  # a failure while working, not bad input: each job of the task reported with it
            results = [{"error": str(e), "loaded": False, "warnings": [], "files": []} for _ in group]
        for (n, _), result in zip(group, results):
            if "error" in result:
                failures.append((n, result["error"]))
            loads += result["loaded"]
            warnings += result["warnings"]
            _remove_leftovers(result["files"])
        done += len(group)
        if progress:
            progress(done, len(numbered))
    return BatchReport(len(numbered), sorted(failures), loads, time.perf_counter() - started, _unique(warnings))


def accuracy(arguments, client, *, executable=None, progress=None):
    """Runs `cuberille accuracy ARGUMENTS` (the scene and options, as on the command line) on the
    client's cluster, writing the report the tool writes. Each setting's runs are one task; the
    ground truth, the longest, is handed out first. `executable` is the cuberille program the
    runs start (by default $CUBERILLE_BINARY, else `cuberille` on PATH): a path that names it on
    every worker, as the scene and --out must. Times are each worker's: a worker sharing its
    machine with others measures with their load beside it (docs/scale-out.md). Raises InputError
    as the tool refuses. `progress`, if given, is called with (settings done, settings in all)."""
    started = time.perf_counter()
    arguments = [os.fspath(a) for a in arguments]
    command = _cuberille.AccuracyCommand.from_arguments(arguments)
    program = _cuberille_program(executable)
    threads = _threads_per_worker(client)
    runs = command.plan(program, threads)
    truth = len(runs) - 1
    futures = {client.submit(_accuracy_run, arguments, runs[i], program, threads, pure=False,
                             priority=1 if i == truth else 0, key=f"cuberille-accuracy-{i}-{_stamp()}"): i
               for i in [truth, *range(truth)]}
    rows = [None] * len(runs)
    for future, result in _gather(client, list(futures), len(runs), progress):
        rows[futures[future]] = result["row"]
    count = command.finish(rows, _cluster_description(client))
    return AccuracyReport(command.out_dir, count, len(runs), _worker_count(client), time.perf_counter() - started)


def fly(arguments, client, *, frames_per_task=None, progress=None):
    """Runs `cuberille fly ARGUMENTS` (the model and options, as on the command line) on the
    client's cluster: the path's frames in contiguous runs (`frames_per_task`; by default four
    runs a worker), each flown from a cold start on a worker, which writes the frames --save-every
    asks for; the run that ends the path settles and writes final.png; --stats, --plot and the
    summary are written here from every run's frames, as the tool writes them. The settled final
    image is the tool's bit for bit; a frame drawn while blocks are still loading depends on when
    reads finish, on one machine as on many (docs/streaming.md). Raises InputError as the tool
    refuses. `progress`, if given, is called with (frames done, frames in all)."""
    started = time.perf_counter()
    arguments = [os.fspath(a) for a in arguments]
    command = _cuberille.FlyCommand.from_arguments(arguments)
    count = command.frames
    runs, results, workers = _frame_runs(client, _fly_run, arguments, count, frames_per_task, progress, "fly")
    files = []
    if command.out_dir:
        if command.save_every > 0:
            files = [command.frame_file(i) for i in range(0, count, command.save_every)]
        files.append(os.path.join(command.out_dir, "final.png"))
    _remove_leftovers(files)
    ordered = [results[first]["run"] for first, _ in runs]
    command.finish(ordered)
    _remove_leftovers([f for f in (command.stats, command.plot) if f])
    flown = [json.loads(r) for r in ordered]
    warnings = _unique(w for r in flown for w in r["warnings"])
    return FlyReport(files, sum(len(r["frames"]) for r in flown), sum(r["bytesReadFromDisk"] for r in flown), len(runs),
                     workers, time.perf_counter() - started, warnings)


def voxelize(arguments, client, *, chunks_per_task=None, progress=None, merge_progress=None):
    """Runs `cuberille voxelize ARGUMENTS` (the mesh and options, as on the command line) on the
    client's cluster, writing the files `cuberille voxelize` writes, bit for bit. Two rounds of
    tasks, their files in a hidden folder beside the output: the input's chunks in runs
    (`chunks_per_task`; by default four runs a worker), each voxelized into a part file; then the
    model's blocks in ranges of whole subtrees of the LOD pyramid (four a worker), each merged
    from every part and its pyramid built up to the split level into a range file. Here, the
    levels above the split are built from the ranges' top blocks and the .cvox written, the rest
    copied a block at a time from the range files: no process holds the finest level
    (docs/scale-out.md). Raises InputError as the tool refuses. `progress`, if given, is called
    with (chunks done, chunks in all) as runs finish, `merge_progress` with (ranges done, ranges in
    all) as ranges do."""
    started = time.perf_counter()
    arguments = [os.fspath(a) for a in arguments]
    command = _cuberille.VoxelizeCommand.from_arguments(arguments)
    chunks = command.chunk_count()
    workers = _worker_count(client)
    runs = _runs_of(chunks, chunks_per_task or _items_per_task(chunks, workers))
    threads = _threads_per_worker(client)
    folder, name = os.path.split(os.path.abspath(command.out))
    parts_folder = os.path.join(folder, f".{name}.parts-{_stamp()}")
    os.makedirs(parts_folder)
    parts = [os.path.join(parts_folder, f"chunks-{first:09d}.cvxp") for first, _ in runs]
    try:
        futures = [client.submit(_voxelize_run, arguments, first, n, part, threads, pure=False,
                                 key=f"cuberille-voxelize-{first}-{_stamp()}") for (first, n), part in zip(runs, parts)]
        _gather(client, futures, chunks, progress, lambda r: r["count"])
        plan = command.plan_ranges(parts, 4 * workers)
        ranges = [os.path.join(parts_folder, f"range-{k:06d}.cvxr") for k in range(len(json.loads(plan)["rangeStarts"]))]
        futures = [client.submit(_voxelize_range, arguments, parts, plan, k, path, threads, pure=False,
                                 key=f"cuberille-voxelize-range-{k}-{_stamp()}") for k, path in enumerate(ranges)]
        results = {r["range"]: r["result"] for _, r in _gather(client, futures, len(ranges), merge_progress)}
        command.finish(parts, plan, ranges, [results[k] for k in range(len(ranges))])
    finally:
        shutil.rmtree(parts_folder, ignore_errors=True)
    _remove_leftovers([f for f in (command.out, command.stats, command.export_voxels) if f])
    return VoxelizeReport(command.out, chunks, len(runs), len(ranges), workers, time.perf_counter() - started)


# What runs on the workers: module-level functions, so Dask sends them by name and each worker
# process keeps this module's scene cache between tasks.

_scenes = {}


def _scene(command):
    """The worker's loaded scene for the command, and whether this call loaded it."""
    key = (command.scene, command.detail, command.up_axis)
    if key in _scenes:
        return _scenes[key], False
    scene = Scene(command.scene, detail=command.detail, up_axis=command.up_axis)
    _scenes[key] = scene
    return scene, True


def _render_run(arguments, first, count, threads):
    try:
        command = _cuberille.RenderCommand.from_arguments(arguments)
        scene, _ = _scene(command)
        stats = command.run(scene._scene, first, count, threads)
    except InputError as e:  # returned, not raised: bad input is not retried, and the message stays the tool's
        return {"error": str(e)}
    return {"first": first, "count": count, "stats": stats, "warnings": scene.warnings}


def _batch_jobs(group, threads):
    """Each (line number, job line) of the group in turn; a job's failure does not stop the next."""
    return [_batch_job(line, threads) for _, line in group]


def _batch_job(line, threads):
    try:
        command = _cuberille.RenderCommand.from_job_line(line)
        scene, loaded = _scene(command)
        files = [command.frame_file(i) for i in range(command.frame_count)] + ([command.stats] if command.stats else [])
        stats = command.run(scene._scene, 0, command.frame_count, threads)
        if command.stats:
            command.write_stats(stats)
        return {"loaded": loaded, "warnings": scene.warnings, "files": files}
    except InputError as e:
        return {"error": str(e), "loaded": False, "warnings": [], "files": []}


def _fly_run(arguments, first, count, threads):
    try:
        command = _cuberille.FlyCommand.from_arguments(arguments)
        return {"first": first, "count": count, "run": command.run(first, count, threads)}
    except InputError as e:
        return {"error": str(e)}


def _voxelize_run(arguments, first, count, part, threads):
    try:
        _cuberille.VoxelizeCommand.from_arguments(arguments).run(first, count, part, threads)
        return {"first": first, "count": count}
    except InputError as e:
        return {"error": str(e)}


def _voxelize_range(arguments, parts, plan, k, path, threads):
    try:
        return {"range": k, "result": _cuberille.VoxelizeCommand.from_arguments(arguments).merge_range(parts, plan, k, path, threads)}
    except InputError as e:
        return {"error": str(e)}


def _accuracy_run(arguments, run, executable, threads):
    try:
        command = _cuberille.AccuracyCommand.from_arguments(arguments)
        return {"row": command.run(run, executable, threads)}
    except InputError as e:  # a render the tool calls bad input (exit 2): its message, not a retry
        return {"error": str(e)}


# Details.

def _worker_count(client):
    return max(1, len(client.scheduler_info().get("workers", {})))


def _threads_per_worker(client):
    """Render threads for a command that did not choose --threads: the cores of a worker's machine
    shared among the worker processes on it, so two workers on two cores do not each run two (the
    fewest any machine of the cluster gives, since a task does not choose its worker)."""
    cores = client.run(os.cpu_count)  # worker address -> its machine's cores
    per_host = {}
    for address in cores:
        host = address.rsplit(":", 1)[0]
        per_host[host] = per_host.get(host, 0) + 1
    shares = [(cores[a] or 1) // per_host[a.rsplit(":", 1)[0]] for a in cores]
    return max(1, min(shares, default=os.cpu_count() or 1))


def _cuberille_program(executable):
    """The cuberille program an accuracy run starts: the one given, $CUBERILLE_BINARY, or
    `cuberille` on PATH; absolute, so a worker started in another folder finds it too."""
    program = executable or os.environ.get("CUBERILLE_BINARY") or shutil.which("cuberille")
    if not program or not os.access(program, os.X_OK):
        raise InputError("accuracy: cannot find the cuberille program " + (f"'{program}' " if program else "") +
                         "(give its path with --cuberille, set CUBERILLE_BINARY, or put it on PATH)")
    return os.path.abspath(program)


def _cluster_description(client):
    """The report's machine line for a sweep run on a cluster: its worker processes and machines."""
    cores = client.run(os.cpu_count)
    hosts = {}
    for address, count in cores.items():
        host = address.rsplit(":", 1)[0]
        hosts.setdefault(host, [0, count])[0] += 1
    machines = ", ".join(f"{host} ({workers} worker{'s' if workers != 1 else ''}, {count} cores)"
                         for host, (workers, count) in sorted(hosts.items()))
    return f"Dask cluster of {len(cores)} worker processes: {machines}"


def _runs_of(count, per_task):
    """Frames 0..count-1 as contiguous (first, count) runs of per_task frames."""
    return [(first, min(per_task, count - first)) for first in range(0, count, per_task)]


def _frame_runs(client, task, arguments, count, frames_per_task, progress, name):
    """A sequence's frames 0..count-1 in contiguous runs, one task each: task(arguments, first, n,
    threads) on a worker, returning {"first": first, "count": n, ...}. The runs, each run's result
    by its first frame, and the workers."""
    workers = _worker_count(client)
    runs = _runs_of(count, frames_per_task or _items_per_task(count, workers))
    threads = _threads_per_worker(client)
    futures = [client.submit(task, arguments, first, n, threads, pure=False, key=f"cuberille-{name}-{first}-{_stamp()}")
               for first, n in runs]
    results = {r["first"]: r for _, r in _gather(client, futures, count, progress, lambda r: r["count"])}
    return runs, results, workers


def _gather(client, futures, total, progress, done_by=lambda result: 1):
    """(future, result) of each task as it finishes. A result that is the tool's refusal of bad
    input ({"error": message}) raises InputError with it; the tasks not finished are cancelled
    then, and on any other failure. `progress`, if given, hears (done, total), each result adding
    done_by(result)."""
    from distributed import as_completed

    finished, done = [], 0
    try:
        for future in as_completed(futures):
            result = future.result()
            if "error" in result:
                raise InputError(result["error"])
            finished.append((future, result))
            done += done_by(result)
            if progress:
                progress(done, total)
    finally:
        client.cancel(futures)
    return finished


def _items_per_task(items, workers):
    """Runs of frames (or of batch jobs): four a worker, so a slow or lost worker costs a quarter
    of its share, while a run stays long enough for its frames to reuse the hierarchies its first
    frame built, and a batch of many small jobs costs a few tasks, not one each (a task costs
    about 2 ms of the scheduler's time: docs/scale-out.md)."""
    return max(1, math.ceil(items / (4 * workers)))


def _remove_leftovers(files):
    """Temporary files left by a worker killed while writing: every task has finished, so none of
    them is still being written. The tool names them .NAME.tmpPID (apps/atomic_file.cpp: stats,
    depth planes) or, for images, whose writer picks the format by extension, .STEM.tmpPID.EXT
    (apps/image_io.cpp)."""
    for path in files:
        folder, name = os.path.split(path)
        stem, extension = os.path.splitext(name)
        folder = glob.escape(folder or ".")
        patterns = [glob.escape("." + name) + ".tmp*", glob.escape("." + stem) + ".tmp*" + glob.escape(extension)]
        for pattern in patterns:
            for leftover in glob.glob(os.path.join(folder, pattern)):
                try:
                    os.remove(leftover)
                except OSError:
                    pass


def _unique(items):
    seen, out = set(), []
    for item in items:
        if item not in seen:
            seen.add(item)
            out.append(item)
    return out


_counter = [0]


def _stamp():
    """Keys unique within this process, so two runs of the same command are two sets of tasks."""
    _counter[0] += 1
    return f"{os.getpid()}-{_counter[0]}"


def _print_progress(what):
    """A progress line on a terminal, nothing when piped (DESIGN.md's command-line conventions)."""
    if not sys.stderr.isatty():
        return None

    def show(done, total):
        sys.stderr.write(f"\r{what}: {done}/{total}")
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show
