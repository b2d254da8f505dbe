"""python3 -m cuberille.dask render|batch|accuracy|fly|voxelize ...: the tool's commands on a Dask cluster.

    python3 -m cuberille.dask render SCENE [cuberille render's options] [--scheduler tcp://host:8786]
    python3 -m cuberille.dask batch JOBS.jsonl [--quiet] [--scheduler ...]
    python3 -m cuberille.dask accuracy SCENE --out DIR [cuberille accuracy's options] [--scheduler ...]
    python3 -m cuberille.dask fly MODEL.cvox [cuberille fly's options] [--scheduler ...]
    python3 -m cuberille.dask voxelize MESH -o MODEL.cvox [cuberille voxelize's options] [--scheduler ...]

The files written are the ones `cuberille render`, `cuberille batch`, `cuberille accuracy` and
`cuberille fly` and `cuberille voxelize` write for the same options (an accuracy report's times and machine are the
cluster's; a flight's frames drawn while blocks load depend on when reads finish); exit codes as the tool's (0 done, 1 a failure while working, 2 bad input). With no
--scheduler, a LocalCluster on this machine (--workers processes, one task at a time each).
"""

import os
import sys

USAGE = """usage: python3 -m cuberille.dask COMMAND ... [--scheduler ADDRESS] [--workers N]

Cuberille's commands on a Dask cluster, writing the files the tool writes (docs/scale-out.md).

commands:
  render SCENE [OPTIONS]   `cuberille render` with any of its options (cuberille render --help);
                           --turntable and --animate frames run as tasks of contiguous frames
  batch JOBS.jsonl         `cuberille batch`: tasks of consecutive job lines
  accuracy SCENE --out DIR [OPTIONS]
                           `cuberille accuracy` with any of its options: each setting's runs
                           are a task; the report is written here
  fly MODEL.cvox [OPTIONS] `cuberille fly` with any of its options: runs of the path's frames,
                           each flown from a cold start; CSV, plot and summary written here
  voxelize MESH -o OUT.cvox [OPTIONS]
                           `cuberille voxelize` with any of its options: runs of the input's
                           chunks voxelized on the workers, merged and written here

options of every command:
  --scheduler ADDRESS      a running Dask scheduler (tcp://host:8786); default: a LocalCluster here
  --workers N              the LocalCluster's worker processes (default: this machine's cores)
  --frames-per-task N      frames (render, fly), job lines (batch) or chunks (voxelize) in one
                           task (default: a quarter of a worker's share)
  --cuberille PATH         accuracy: the cuberille program its runs start, a path every worker
                           sees (default: $CUBERILLE_BINARY, else cuberille on PATH)
  --quiet                  print only failures
"""


def main(argv):
    if not argv or argv[0] in ("-h", "--help"):
        print(USAGE, end="")
        return 0 if argv else 2
    command, rest = argv[0], argv[1:]
    if command not in ("render", "batch", "accuracy", "fly", "voxelize"):
        sys.stderr.write(f"cuberille.dask: unknown command '{command}' (render, batch, accuracy, fly or voxelize)\n")
        return 2
    if "-h" in rest or "--help" in rest:
        print(USAGE, end="")
        return 0
    try:
        own, rest = _own_options(rest)
    except ValueError as e:
        sys.stderr.write(f"cuberille.dask: {e}\n")
        return 2
    quiet = own["quiet"] or (command in ("render", "accuracy", "fly", "voxelize") and "--quiet" in rest)

    import cuberille.dask as cd
    from cuberille import InputError

    if not _have("distributed"):
        sys.stderr.write(f"cuberille.dask: Dask's distributed is not installed for {sys.executable} "
                         "(Debian: python3-distributed; .ci/install-deps installs it)\n")
        return 1

    try:
        with _client(own, quiet) as client:
            if command == "render":
                report = cd.render(rest, client, frames_per_task=own["frames_per_task"],
                                   progress=None if quiet else cd._print_progress("frames"))
                _print_warnings(report.warnings, quiet)
                if not quiet:
                    first, last = report.files[0], report.files[-1]
                    print(f"wrote {first}" + (f" .. {last} ({len(report.files)} frames" if len(report.files) > 1 else " (1 frame")
                          + f", {report.tasks} task{'s' if report.tasks != 1 else ''} on {report.workers} "
                          f"worker{'s' if report.workers != 1 else ''}); {report.seconds:.2f} s")
                return 0
            if command == "accuracy":
                report = cd.accuracy(rest, client, executable=own["cuberille"],
                                     progress=None if quiet else cd._print_progress("settings"))
                if not quiet:
                    print(f"wrote {report.rows} settings to {report.folder} (index.html, report.csv, report.json); "
                          f"{report.tasks} tasks on {report.workers} worker{'s' if report.workers != 1 else ''}, "
                          f"{report.seconds:.2f} s")
                return 0
            if command == "fly":
                report = cd.fly(rest, client, frames_per_task=own["frames_per_task"],
                                progress=None if quiet else cd._print_progress("frames"))
                _print_warnings(report.warnings, quiet)
                if not quiet:
                    print(f"  {report.tasks} run{'s' if report.tasks != 1 else ''} on {report.workers} "
                          f"worker{'s' if report.workers != 1 else ''}, each from a cold start; {report.seconds:.2f} s")
                return 0
            if command == "voxelize":
                report = cd.voxelize(rest, client, chunks_per_task=own["frames_per_task"],
                                     progress=None if quiet else cd._print_progress("chunks"),
                                     merge_progress=None if quiet else cd._print_progress("block ranges"))
                if not quiet:
                    print(f"  {report.chunks} chunks in {report.tasks} task{'s' if report.tasks != 1 else ''}, "
                          f"{report.range_tasks} block range{'s' if report.range_tasks != 1 else ''} merged, on "
                          f"{report.workers} worker{'s' if report.workers != 1 else ''}; {report.seconds:.2f} s")
                return 0
            jobs = [a for a in rest if a != "--quiet"]
            if len(jobs) != 1 or jobs[0].startswith("-"):
                raise InputError("batch: one jobs file and no other options (batch JOBS.jsonl)")
            report = cd.batch(jobs[0], client, jobs_per_task=own["frames_per_task"],
                              progress=None if quiet else cd._print_progress("jobs"))
            _print_warnings(report.warnings, quiet)
            for line, message in report.failures:
                sys.stderr.write(f"cuberille batch: {jobs[0]}:{line}: {message}\n")
            if not quiet:
                print(f"batch: {report.jobs} job{'s' if report.jobs != 1 else ''}, {len(report.failures)} failed, "
                      f"{report.scene_loads} scene load{'s' if report.scene_loads != 1 else ''} on the workers; "
                      f"{report.seconds * 1000.0:.1f} ms")
            return 1 if report.failures else 0
    except InputError as e:
        sys.stderr.write(f"cuberille: {e}\n")
        return 2
    except Exception as e:  # a failure while working: a task that kept failing, a lost scheduler
        sys.stderr.write(f"cuberille: {e}\n")
        return 1


def _own_options(arguments):
    """This runner's options taken out of the arguments; the rest are the tool command's."""
    own = {"scheduler": None, "workers": os.cpu_count() or 1, "frames_per_task": None, "quiet": False, "cuberille": None}
    rest, i = [], 0
    while i < len(arguments):
        a = arguments[i]
        name, _, inline = a.partition("=")
        if name in ("--scheduler", "--workers", "--frames-per-task", "--cuberille"):
            value = inline if inline else (arguments[i + 1] if i + 1 < len(arguments) else None)
            if value is None:
                raise ValueError(f"{name}: a value is required")
            i += 1 if inline else 2
            if name in ("--scheduler", "--cuberille"):
                own[name[2:]] = value
            else:
                try:
                    number = int(value)
                except ValueError:
                    number = 0
                if number < 1:
                    raise ValueError(f"{name}: a whole number of at least 1, not '{value}'")
                own[name[2:].replace("-", "_")] = number
            continue
        if a == "--quiet":
            own["quiet"] = True
        rest.append(a)  # --quiet also belongs to render's own options
        i += 1
    return own, rest


class _client:
    """A Client of the given scheduler, or of a LocalCluster started here and closed afterwards."""

    def __init__(self, own, quiet):
        self.own, self.quiet, self.cluster = own, quiet, None

    def __enter__(self):
        import logging

        from distributed import Client, LocalCluster

        if self.own["scheduler"]:
            self.client = Client(self.own["scheduler"])
        else:
            # Dask's own warnings (a worker restarted after a crash, an event loop slow under load) stay
            # out of stderr, here and in the worker processes: stderr carries the tool's messages.
            logging.getLogger("distributed").setLevel(logging.ERROR)
            # ":0": a free port for the scheduler's HTTP server (the dashboard where Bokeh is installed),
            # never a warning that the default 8787 is taken by another cluster
            self.cluster = LocalCluster(n_workers=self.own["workers"], threads_per_worker=1, processes=True,
                                        dashboard_address=":0", silence_logs=logging.ERROR)
            self.client = Client(self.cluster)
        link = self.client.dashboard_link if _have("bokeh") else None
        if link and not self.quiet:
            sys.stderr.write(f"cuberille.dask: Dask dashboard at {link}\n")
        return self.client

    def __exit__(self, *exc):
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        return False


def _have(module):
    import importlib.util

    return importlib.util.find_spec(module) is not None


def _print_warnings(warnings, quiet):
    if not quiet:
        for w in warnings:
            sys.stderr.write(f"cuberille: warning: {w}\n")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
