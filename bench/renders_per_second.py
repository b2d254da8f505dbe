#!/usr/bin/env python3
"""Small renders per second, side by side in one run: many thumbnails of one model through
  - Mesa's llvmpipe, a process per image (bench/llvmpipe_render: the peer),
  - `cuberille render`, a process per image,
  - `cuberille batch`, one process for all,
  - the Python module: cuberille.render per image (a load each), and one Scene rendered N times.
Usage (from the repository root, after `make`):
  python3 bench/renders_per_second.py [--build build/release] [--images 40] [--size 320x240] [--msaa 4]
Prints a Markdown table for docs/performance.md. Every image is written (PNG) except the Python
module's, which stay arrays, as a test would compare them."""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPOSITORY = Path(__file__).resolve().parents[1]


def timed(run):
    start = time.perf_counter()
    run()
    return time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=str(REPOSITORY / "build" / "release"))
    parser.add_argument("--images", type=int, default=40)
    parser.add_argument("--size", default="320x240")
    parser.add_argument("--msaa", type=int, default=4)
    parser.add_argument("--model", help="a mesh file (default: the examples' torus.ply)")
    args = parser.parse_args()
    build = Path(args.build)
    sys.path.insert(0, str(build / "python"))
    import cuberille  # noqa: E402  (the build's package)

    width, height = (int(v) for v in args.size.split("x"))
    tool, peer = build / "apps" / "cuberille", build / "bench" / "llvmpipe_render"
    with tempfile.TemporaryDirectory() as work:
        work = Path(work)
        subprocess.run([sys.executable, str(REPOSITORY / "examples" / "make_examples.py"), str(work)], check=True,
                       stdout=subprocess.DEVNULL)
        model = Path(args.model) if args.model else work / "torus.ply"
        frame = ["--width", str(width), "--height", str(height), "--msaa", str(args.msaa)]
        azimuths = [float(9 * i) for i in range(args.images)]
        rows = []

        def processes(command):
            for i, azimuth in enumerate(azimuths):
                subprocess.run(command(i, azimuth), check=True, stdout=subprocess.DEVNULL)

        if peer.exists():
            rows.append(("llvmpipe, a process per image (peer)",
                         timed(lambda: processes(lambda i, a: [str(peer), str(model), "--out", str(work / f"p{i}.png"), *frame]))))
        rows.append(("`cuberille render`, a process per image",
                     timed(lambda: processes(lambda i, a: [str(tool), "render", str(model), *frame, "--azimuth", str(a),
                                                           "--quiet", "--out", str(work / f"r{i}.png")]))))
        jobs = work / "jobs.jsonl"
        jobs.write_text("".join(json.dumps({"scene": str(model), "out": str(work / f"b{i}.png"), "width": width, "height": height,
                                            "msaa": args.msaa, "azimuth": a}) + "\n" for i, a in enumerate(azimuths)))
        rows.append(("`cuberille batch`, one process", timed(lambda: subprocess.run([str(tool), "batch", str(jobs), "--quiet"], check=True))))
        rows.append(("Python `cuberille.render` (a load per image)",
                     timed(lambda: [cuberille.render(model, width, height, args.msaa, azimuth=a) for a in azimuths])))
        scene = cuberille.Scene(model)
        rows.append(("Python `Scene.render` (one load)",
                     timed(lambda: [scene.render(width, height, args.msaa, azimuth=a) for a in azimuths])))

    peer_rate = args.images / rows[0][1] if peer.exists() else None
    print(f"{args.images} images of {model.name}, {width}x{height}, {args.msaa} samples, {os.cpu_count()} cores\n")
    print("| path | images/s | ms an image | vs llvmpipe processes |")
    print("|---|---:|---:|---:|")
    for name, seconds in rows:
        rate = args.images / seconds
        ratio = f"{rate / peer_rate:.2f}x" if peer_rate else "-"
        print(f"| {name} | {rate:.1f} | {1000 * seconds / args.images:.1f} | {ratio} |")


if __name__ == "__main__":
    main()
