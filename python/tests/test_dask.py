"""cuberille.dask on a LocalCluster of two worker processes against the tool on one machine: the
same files bit for bit for a turntable, an animation and a batch; a worker killed mid-run costs
nothing but time; bad input fails with the tool's message and the other jobs finish."""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

distributed = pytest.importorskip("distributed", reason="Dask's python3-distributed is not installed (.ci/install-deps)")

import cuberille
import cuberille.dask


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        with distributed.Client(cluster) as c:
            yield c


def run_cli(cli, *arguments, cwd=None):
    return subprocess.run([cli, *map(str, arguments)], cwd=cwd, capture_output=True, text=True)


def files_of(folder):
    """Every file in the folder, hidden ones included (a leftover temporary file is one)."""
    return {p.name: p.read_bytes() for p in sorted(Path(folder).iterdir())}


def sequence_case(examples, kind):
    if kind == "turntable":
        return [examples / "knot.obj", "--turntable", "12", "--width", "96", "--height", "72", "--msaa", "4",
                "--shadows", "raytraced"]
    return [examples / "spinning-box.gltf", "--animate", "9", "--fps", "6", "--width", "96", "--height", "72",
            "--shadows", "hybrid", "--frustum-cull"]


@pytest.mark.parametrize("kind", ["turntable", "animation"])
def test_a_sequence_writes_the_files_the_cli_writes(examples, cli, client, tmp_path, kind):
    (tmp_path / "cli").mkdir(), (tmp_path / "dask").mkdir()
    arguments = sequence_case(examples, kind)
    assert run_cli(cli, "render", *arguments, "--out", tmp_path / "cli" / "f.png", "--quiet").returncode == 0
    # Runs of 2 frames: runs start mid-sequence, so a run's first frame builds what the tool's refits
    report = cuberille.dask.render([*arguments, "--out", tmp_path / "dask" / "f.png", "--stats", tmp_path / "s.json"],
                                   client, frames_per_task=2)
    assert report.tasks > 1 and len(report.files) == len(report.frame_stats)
    assert files_of(tmp_path / "dask") == files_of(tmp_path / "cli")
    stats = json.loads((tmp_path / "s.json").read_text())
    assert len(stats["frames"]) == len(report.files)


def test_the_temporary_files_of_a_killed_writer_are_removed_and_nothing_else(tmp_path):
    """What a worker killed between writing and renaming leaves, in both of the tool's namings
    (apps/atomic_file.cpp, apps/image_io.cpp), is removed; the outputs and a look-alike are not.
    The killed-worker test below reaches this only when the kill lands mid-write."""
    names = ["f_003.png", ".f_003.tmp4242.png", "stats.json", ".stats.json.tmp4242", ".f_003.png.tmp7",
             "f_0030.png", ".f_0030.tmp1.png", "other.png"]
    for name in names:
        (tmp_path / name).write_bytes(b"x")
    cuberille.dask._remove_leftovers([str(tmp_path / "f_003.png"), str(tmp_path / "stats.json")])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [".f_0030.tmp1.png", "f_0030.png", "f_003.png", "other.png", "stats.json"])


def test_a_worker_killed_mid_run_leaves_every_frame_whole(examples, cli, client, tmp_path):
    (tmp_path / "cli").mkdir(), (tmp_path / "dask").mkdir()
    arguments = [examples / "knot.obj", "--turntable", "24", "--width", "320", "--height", "240", "--msaa", "4",
                 "--shadows", "raytraced", "--threads", "1"]
    assert run_cli(cli, "render", *arguments, "--out", tmp_path / "cli" / "f.png", "--quiet").returncode == 0
    pids = client.run(os.getpid)
    killed = []

    def kill_one_worker(done, total):
        if not killed:  # after the first run finished, while the others are being drawn
            victim = sorted(pids.values())[0]
            os.kill(victim, signal.SIGKILL)
            killed.append(victim)

    cuberille.dask.render([*arguments, "--out", tmp_path / "dask" / "f.png"], client, frames_per_task=1,
                          progress=kill_one_worker)
    assert killed and killed[0] not in client.run(os.getpid).values()  # the worker died (and its nanny restarted it)
    assert files_of(tmp_path / "dask") == files_of(tmp_path / "cli")  # no frame missing, torn or left as a temporary file
    client.wait_for_workers(2)


def test_a_batch_writes_the_files_the_cli_writes_and_a_bad_job_fails_alone(examples, cli, client, tmp_path):
    (tmp_path / "cli").mkdir(), (tmp_path / "dask").mkdir()
    jobs = []
    for azimuth in (0, 120, 240):
        jobs.append({"scene": str(examples / "torus.ply"), "out": f"torus-{azimuth}.png", "width": 80, "height": 60,
                     "msaa": 4, "azimuth": azimuth})
    jobs.append({"scene": str(examples / "missing.ply"), "out": "missing.png"})
    jobs.append({"scene": str(examples / "spinning-box.gltf"), "out": "box.png", "width": 80, "height": 60,
                 "time": 0.5, "shadows": "hybrid", "stats": "box.json"})
    jobs.append({"scene": str(examples / "knot.obj"), "out": "knot.png", "msaa": 3})
    text = "# a comment, then the jobs\n\n" + "\n".join(json.dumps(j) for j in jobs) + "\n"
    for folder in ("cli", "dask"):
        (tmp_path / folder / "jobs.jsonl").write_text(text)
    expected = run_cli(cli, "batch", "jobs.jsonl", "--quiet", cwd=tmp_path / "cli")
    assert expected.returncode == 1

    # The jobs' relative outputs are the workers' and this process's folder: the cluster's processes started here
    here = os.getcwd()
    os.chdir(tmp_path / "dask")
    try:
        remote_cwd = client.run(os.getcwd)
        client.run(os.chdir, str(tmp_path / "dask"))
        report = cuberille.dask.batch("jobs.jsonl", client, jobs_per_task=2)  # a task holds a failing job and a good one
    finally:
        for address, folder in remote_cwd.items():
            client.run(os.chdir, folder, workers=[address])
        os.chdir(here)
    assert report.jobs == 6
    messages = [f"cuberille batch: jobs.jsonl:{line}: {message}" for line, message in report.failures]
    assert messages == expected.stderr.splitlines()  # the same lines, messages and order as the tool
    cli_files, dask_files = files_of(tmp_path / "cli"), files_of(tmp_path / "dask")
    assert cli_files.keys() == dask_files.keys()
    for name in cli_files:
        if name != "box.json":  # --stats holds times
            assert dask_files[name] == cli_files[name], name
    assert json.loads(dask_files["box.json"]).keys() == json.loads(cli_files["box.json"]).keys()


def test_the_command_line_runs_on_a_running_scheduler(examples, cli, client, tmp_path):
    """`--scheduler ADDRESS`: the command line joins a cluster that is already running (here the
    module's two-worker cluster, as a user's `dask scheduler` would be) instead of starting one,
    and a turntable and a voxelization write the tool's files."""
    (tmp_path / "cli").mkdir(), (tmp_path / "dask").mkdir()
    address = client.scheduler.address
    turntable = [examples / "knot.obj", "--turntable", "4", "--width", "64", "--height", "48"]
    voxelize = [examples / "knot.obj", "--resolution", "256"]
    assert run_cli(cli, "render", *turntable, "--out", tmp_path / "cli" / "t.png", "--quiet").returncode == 0
    assert run_cli(cli, "voxelize", *voxelize, "-o", tmp_path / "cli" / "m.cvox", "--quiet").returncode == 0
    for command, arguments, out in (("render", turntable, ["--out", tmp_path / "dask" / "t.png"]),
                                    ("voxelize", voxelize, ["-o", tmp_path / "dask" / "m.cvox"])):
        done = subprocess.run([sys.executable, "-m", "cuberille.dask", command, *map(str, arguments + out),
                               "--scheduler", address], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        assert "2 workers" in done.stdout, done.stdout
    assert files_of(tmp_path / "dask") == files_of(tmp_path / "cli")


def test_the_command_line_gives_the_tools_files_and_exit_codes(examples, cli, tmp_path):
    (tmp_path / "cli").mkdir(), (tmp_path / "dask").mkdir()
    arguments = [examples / "torus.ply", "--turntable", "4", "--width", "64", "--height", "48"]
    assert run_cli(cli, "render", *arguments, "--out", tmp_path / "cli" / "t.png", "--quiet").returncode == 0
    command = [sys.executable, "-m", "cuberille.dask", "render", *map(str, arguments), "--out",
               str(tmp_path / "dask" / "t.png"), "--workers", "2"]
    done = subprocess.run(command, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "4 frames" in done.stdout
    assert files_of(tmp_path / "dask") == files_of(tmp_path / "cli")

    bad = [str(examples / "missing.ply"), "--out", str(tmp_path / "x.png")]
    tool = run_cli(cli, "render", *bad)
    ours = subprocess.run([sys.executable, "-m", "cuberille.dask", "render", *bad, "--workers", "1"],
                          capture_output=True, text=True)
    assert (ours.returncode, ours.stderr) == (tool.returncode, tool.stderr) == (2, tool.stderr)
    assert "missing.ply" in ours.stderr

    bad_option = subprocess.run([sys.executable, "-m", "cuberille.dask", "render", str(examples / "torus.ply"),
                                 "--msaa", "3", "--out", str(tmp_path / "y.png")], capture_output=True, text=True)
    assert bad_option.returncode == 2 and bad_option.stderr == run_cli(cli, "render", examples / "torus.ply", "--msaa",
                                                                       "3", "--out", tmp_path / "y.png").stderr


def report_rows(folder, drop_folder):
    """report.csv's rows without the columns that are times or memory, the report's folder in
    each command line replaced, so two runs' rows compare."""
    import csv

    with open(folder / "report.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    timed = ("median_ms", "min_ms", "max_ms", "setup_ms", "peak_mib", "pareto")
    return [{k: v.replace(str(drop_folder), "OUT") for k, v in row.items() if k not in timed} for row in rows]


def test_an_accuracy_sweep_writes_the_report_the_cli_writes(examples, cli, client, tmp_path):
    """Every row's error against the ground truth, its command line and its comparison crop are the
    tool's (the renders are the same pixels; an EXR also holds the time it was written); a command
    line several knobs share is rendered once."""
    arguments = [examples / "knot.obj", "--width", "40", "--height", "30", "--frames", "1", "--threads", "1"]
    assert run_cli(cli, "accuracy", *arguments, "--out", tmp_path / "cli", "--quiet").returncode == 0
    report = cuberille.dask.accuracy([*arguments, "--out", tmp_path / "dask", "--quiet"], client, executable=cli)
    expected = report_rows(tmp_path / "cli", tmp_path / "cli")
    assert report.rows == len(expected) and 1 < report.tasks < report.rows
    assert report_rows(tmp_path / "dask", tmp_path / "dask") == expected
    assert files_of(tmp_path / "dask" / "crops") == files_of(tmp_path / "cli" / "crops")
    assert sorted(os.listdir(tmp_path / "dask" / "renders")) == sorted(os.listdir(tmp_path / "cli" / "renders"))
    machine = json.loads((tmp_path / "dask" / "report.json").read_text())["machine"]
    assert machine.startswith("Dask cluster of 2 worker processes")


def test_an_accuracy_sweep_refuses_what_the_tool_refuses_with_its_message(examples, cli, tmp_path):
    # --threads given: left at 0 (all cores), a worker's runs take its share of its machine's cores,
    # and the probe's command line in the message says so
    for arguments in ([examples / "missing.ply", "--out", tmp_path / "r", "--threads", "1"],
                      [examples / "knot.obj", "--frames", "0", "--out", tmp_path / "r"]):
        tool = run_cli(cli, "accuracy", *arguments)
        ours = subprocess.run([sys.executable, "-m", "cuberille.dask", "accuracy", *map(str, arguments), "--workers", "1",
                               "--cuberille", cli], capture_output=True, text=True)
        assert (ours.returncode, ours.stderr) == (tool.returncode, tool.stderr) == (2, tool.stderr)
    nowhere = subprocess.run([sys.executable, "-m", "cuberille.dask", "accuracy", str(examples / "knot.obj"), "--out",
                              str(tmp_path / "r"), "--workers", "1", "--cuberille", str(tmp_path / "no-such-program")],
                             capture_output=True, text=True)
    assert nowhere.returncode == 2 and "cannot find the cuberille program" in nowhere.stderr


def test_a_flight_in_runs_writes_the_tools_files_and_settles_on_its_final_image(examples, cli, client, tmp_path):
    """Runs of 3 frames, each from a cold start: the frames --save-every asks for are there under
    the tool's names (what a frame shows while blocks load depends on when reads finish, on one
    machine as on many), the settled final image is the tool's bit for bit, and the CSV has the
    tool's columns and one row per frame of the path in order, then the last run's settling."""
    import csv

    model = tmp_path / "torus.cvox"
    assert run_cli(cli, "voxelize", examples / "torus.ply", "--resolution", "128", "-o", model, "--quiet").returncode == 0
    arguments = [model, "--frames", "8", "--width", "96", "--height", "72", "--msaa", "1", "--budget-mib", "4",
                 "--save-every", "2"]
    assert run_cli(cli, "fly", *arguments, "--out-dir", tmp_path / "cli", "--stats", tmp_path / "cli.csv",
                   "--quiet").returncode == 0
    report = cuberille.dask.fly([*arguments, "--out-dir", tmp_path / "dask", "--stats", tmp_path / "dask.csv",
                                 "--plot", tmp_path / "dask-plot.png", "--quiet"], client, frames_per_task=3)
    assert report.tasks == 3 and report.frames >= 8
    assert sorted(os.listdir(tmp_path / "dask")) == sorted(os.listdir(tmp_path / "cli")) == \
        ["final.png", "frame_00000.png", "frame_00002.png", "frame_00004.png", "frame_00006.png"]
    assert (tmp_path / "dask" / "final.png").read_bytes() == (tmp_path / "cli" / "final.png").read_bytes()
    with open(tmp_path / "cli.csv", newline="") as f:
        tool = list(csv.DictReader(f))
    with open(tmp_path / "dask.csv", newline="") as f:
        ours = list(csv.DictReader(f))
    assert list(ours[0].keys())[:30] == list(tool[0].keys())[:30]
    path = [int(r["frame"]) for r in ours if r["settling"] == "0"]
    assert path == list(range(8))
    assert [int(r["frame"]) for r in ours] == list(range(len(ours)))
    assert (tmp_path / "dask-plot.png").stat().st_size > 0

    bad = subprocess.run([sys.executable, "-m", "cuberille.dask", "fly", str(examples / "torus.ply"), "--workers", "1"],
                         capture_output=True, text=True)
    tool_bad = run_cli(cli, "fly", examples / "torus.ply")
    assert (bad.returncode, bad.stderr) == (tool_bad.returncode, tool_bad.stderr) == (2, tool_bad.stderr)


@pytest.mark.parametrize("packed", [True, False])
def test_a_voxelization_in_runs_of_chunks_writes_the_tools_model_bit_for_bit(examples, cli, client, tmp_path, packed):
    """Runs of two chunks merged on the client: the .cvox and the exported voxels are the tool's
    bytes, from a geometry stream (each worker reads its chunks) and from a mesh file alike (cut
    into chunks of 16,384 triangles: the knot's 6,144 are one, so one task); no part file is left behind."""
    mesh = examples / "knot.obj"
    if packed:
        assert run_cli(cli, "pack", mesh, "-o", tmp_path / "knot.cgs", "--chunk-triangles", "700", "--quiet").returncode == 0
        mesh = tmp_path / "knot.cgs"
    options = ["--resolution", "128", "--separability", "6"]
    (tmp_path / "cli").mkdir(), (tmp_path / "dask").mkdir()
    assert run_cli(cli, "voxelize", mesh, *options, "-o", tmp_path / "cli" / "m.cvox", "--export-voxels",
                   tmp_path / "cli" / "v.txt", "--quiet").returncode == 0
    report = cuberille.dask.voxelize([mesh, *options, "-o", tmp_path / "dask" / "m.cvox", "--export-voxels",
                                      tmp_path / "dask" / "v.txt", "--quiet"], client, chunks_per_task=2)
    assert report.tasks == (report.chunks + 1) // 2 and (report.tasks > 2 or not packed)
    assert files_of(tmp_path / "dask") == files_of(tmp_path / "cli")

    tool = run_cli(cli, "voxelize", examples / "missing.cgs", "-o", tmp_path / "x.cvox")
    ours = subprocess.run([sys.executable, "-m", "cuberille.dask", "voxelize", str(examples / "missing.cgs"), "-o",
                           str(tmp_path / "x.cvox"), "--workers", "1"], capture_output=True, text=True)
    assert (ours.returncode, ours.stderr) == (tool.returncode, tool.stderr) == (2, tool.stderr)


@pytest.mark.parametrize("phase", ["chunks", "ranges"])
def test_a_worker_killed_mid_voxelization_leaves_the_tools_model_and_no_part(examples, cli, client, tmp_path, phase):
    """A worker killed after the first run of chunks finished, while the others are voxelized, or
    after the first range of blocks was merged, while the others are: Dask runs its tasks again (a
    part or range file is written atomically, so a killed writer leaves at most a temporary file
    in the parts folder, which goes with it), and the model is the tool's bytes. At 512^3 the
    knot's blocks split at level 1, so the client builds the two levels above from the ranges."""
    assert run_cli(cli, "pack", examples / "knot.obj", "-o", tmp_path / "knot.cgs", "--chunk-triangles", "400",
                   "--quiet").returncode == 0
    options = ["--resolution", "512", "--threads", "1"]
    (tmp_path / "cli").mkdir(), (tmp_path / "dask").mkdir()
    assert run_cli(cli, "voxelize", tmp_path / "knot.cgs", *options, "-o", tmp_path / "cli" / "m.cvox",
                   "--quiet").returncode == 0
    pids = client.run(os.getpid)
    killed = []

    def kill_one_worker(done, total):
        if not killed:
            victim = sorted(pids.values())[0]
            os.kill(victim, signal.SIGKILL)
            killed.append(victim)

    killer = {"progress": kill_one_worker} if phase == "chunks" else {"merge_progress": kill_one_worker}
    report = cuberille.dask.voxelize([tmp_path / "knot.cgs", *options, "-o", tmp_path / "dask" / "m.cvox", "--quiet"],
                                     client, chunks_per_task=1, **killer)
    assert report.tasks > 4 and report.range_tasks > 4
    assert killed and killed[0] not in client.run(os.getpid).values()  # the worker died (and its nanny restarted it)
    assert files_of(tmp_path / "dask") == files_of(tmp_path / "cli")  # the model whole, no part or parts folder left
    client.wait_for_workers(2)

