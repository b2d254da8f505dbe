"""The Python module against the command line and against itself: the same pixels as the PNG
the tool writes, a loaded scene that renders the same frame whatever it rendered before, errors
with the tool's messages, the GIL released while rendering, and the golden-image helper."""

import csv
import subprocess
from pathlib import Path
import threading
import time

import numpy as np
import pytest

import cuberille
from cuberille import testing

# Each case: a scene (a file of the examples, or a built-in scene) and the options of both calls,
# chosen to cover every kind of scene and the outputs that change the bytes (alpha, depth view,
# an animation time, shadows — auto, over the scene, on a floor — a camera placed by hand).
CASES = [
    ("triangles.tri", dict(width=128, height=128, msaa=4), ["--width", "128", "--height", "128", "--msaa", "4"]),
    ("torus.ply", dict(width=160, height=120, msaa=4, azimuth=60.0), ["--width", "160", "--height", "120", "--msaa", "4", "--azimuth", "60"]),
    ("knot.obj", dict(width=160, height=120, background=(1.0, 1.0, 1.0, 0.0)),
     ["--width", "160", "--height", "120", "--background", "1,1,1,0"]),
    ("spinning-box.gltf", dict(width=160, height=120, msaa=2, time=1.25, shadows="hybrid"),
     ["--width", "160", "--height", "120", "--msaa", "2", "--time", "1.25", "--shadows", "hybrid"]),
    ("spinning-box.gltf", dict(width=160, height=120, view="depth", eye=(3.0, 2.0, 4.0), target=(0.0, 0.0, 0.0)),
     ["--width", "160", "--height", "120", "--view", "depth", "--eye", "3,2,4", "--target", "0,0,0"]),
    ("demo", dict(width=160, height=90, msaa=4, detail=0.5), ["--width", "160", "--height", "90", "--msaa", "4", "--detail", "0.5"]),
    ("torus.ply", dict(width=160, height=120, ground=True, shadows="auto", soft=True, shadow_focus="scene"),
     ["--width", "160", "--height", "120", "--ground", "--shadows", "auto", "--soft", "--shadow-focus", "scene"]),
    ("spinning-box.gltf", dict(width=160, height=120, msaa=4, environment="neutral", environment_intensity=1.5, ground=True,
                               shadows="raytraced"),
     ["--width", "160", "--height", "120", "--msaa", "4", "--environment", "neutral", "--environment-intensity", "1.5",
      "--ground", "--shadows", "raytraced"]),
    ("knot.obj", dict(width=160, height=120, ground=True, ao=8, ao_distance=0.5),
     ["--width", "160", "--height", "120", "--ground", "--ao", "8", "--ao-distance", "0.5"]),
    ("knot.obj", dict(width=160, height=120, ground=True, shadows="raytraced", soft=True, accel="grid"),
     ["--width", "160", "--height", "120", "--ground", "--shadows", "raytraced", "--soft", "--accel", "grid"]),
]


def scene_path(examples, name):
    return name if "." not in name else str(examples / name)


@pytest.mark.parametrize("name,options,arguments", CASES, ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)])
def test_render_gives_the_pixels_the_cli_writes(examples, cli, tmp_path, name, options, arguments):
    out = tmp_path / "cli.png"
    subprocess.run([cli, "render", scene_path(examples, name), *arguments, "--out", str(out), "--quiet"], check=True)
    image = cuberille.render(scene_path(examples, name), **options)
    assert image.dtype == np.uint8 and image.shape == (options["height"], options["width"], 4)
    assert np.array_equal(image, cuberille.read_png(str(out)))


def test_a_loaded_scene_renders_each_frame_as_a_fresh_load_does(examples):
    path = str(examples / "spinning-box.gltf")
    scene = cuberille.Scene(path)
    settings = dict(width=96, height=72, msaa=4, shadows="raytraced", frustum_cull=True)
    first = scene.render(time=0.5, **settings)
    scene.render(time=2.0, azimuth=120.0, texture_filter="nearest", **settings)  # another pose, camera, filter
    again = scene.render(time=0.5, **settings)
    assert np.array_equal(first, again)
    assert np.array_equal(first, cuberille.render(path, time=0.5, **settings))


def test_ambient_occlusion_only_takes_ambient_light_away(examples):
    """--ao multiplies the ambient term by the open share of each pixel's hemisphere: no pixel gets
    brighter (one 8-bit level allowed: with occlusion the shade stage leaves its fused one-light
    path, which rounds differently), the knot's crossings and its contact with the ground get
    darker, and the stage reports its rays."""
    scene = cuberille.Scene(str(examples / "knot.obj"))
    settings = dict(width=160, height=120, ground=True)
    plain = scene.render(**settings).astype(int)
    occluded = scene.render(ao=16, **settings).astype(int)
    assert (occluded[..., :3] - plain[..., :3]).max() <= 1
    darker = (plain[..., :3] - occluded[..., :3]).max(axis=-1) >= 2
    assert darker.mean() > 0.02, darker.mean()
    occlusion = scene.stats["ambientOcclusion"]
    assert occlusion["rays"] == 16 * occlusion["pixels"] > 0


def test_the_grid_answers_the_shadow_stages_rays_as_the_bvh_does(examples):
    """accel="grid" (a uniform grid built for the pose) and the default BVH answer every shadow and
    occlusion ray alike, so the pixels are the same; the stats name the structure, and an unknown
    one is refused with the command line's message."""
    scene = cuberille.Scene(str(examples / "knot.obj"))
    settings = dict(width=160, height=120, ground=True, shadows="raytraced", soft=True, ao=4)
    through_bvh = scene.render(**settings)
    assert scene.stats["shadows"]["accel"] == "bvh"
    through_grid = scene.render(accel="grid", **settings)
    assert scene.stats["shadows"]["accel"] == "grid"
    assert np.array_equal(through_grid, through_bvh)
    with pytest.raises(cuberille.InputError, match="--accel: 'octtree' is not bvh, grid, kdtree, octree or bvh8"):
        scene.render(accel="octtree", **settings)
    with pytest.raises(cuberille.InputError, match="--accel octree: a tree over voxels"):
        scene.render(accel="octree", **settings)


def test_a_voxel_model_traced_through_each_tree_is_the_same_image(examples, cli, tmp_path):
    """renderer="raytrace" on a .cvox traces one level's voxels through accel="bvh", "kdtree" or
    "octree": the same pixels from each, and the stats name the tree and count a ray a sample."""
    model = tmp_path / "torus.cvox"
    subprocess.run([cli, "voxelize", str(examples / "torus.ply"), "--resolution", "64", "-o", str(model), "--quiet"], check=True)
    scene = cuberille.Scene(str(model))
    images = {}
    for accel in ("bvh", "kdtree", "octree"):
        images[accel] = scene.render(width=96, height=72, renderer="raytrace", accel=accel)
        assert scene.stats["voxelRays"]["accel"] == accel
        assert scene.stats["voxelRays"]["rays"] == 96 * 72
        assert scene.stats["voxelRays"]["hits"] > 0
    assert np.array_equal(images["bvh"], images["kdtree"])
    assert np.array_equal(images["bvh"], images["octree"])


def test_the_ray_tracer_sees_what_the_rasterizer_sees(examples):
    """renderer="raytrace" finds each sample's surface by a camera ray and shades it with the same
    models: on a mesh on its floor, with ray-traced shadows, the image is the rasterizer's but for
    a few pixels where snapping to 1/256 pixel decides (PrimaryRays' tests bound where); the stats
    report the rays, and a 2D .tri scene is refused."""
    scene = cuberille.Scene(str(examples / "knot.obj"))
    settings = dict(width=160, height=120, ground=True, shadows="raytraced")
    rasterized = scene.render(**settings)
    assert scene.stats["renderer"] == "raster" and "primaryRays" not in scene.stats
    traced = scene.render(renderer="raytrace", **settings)
    rays = scene.stats["primaryRays"]
    assert scene.stats["renderer"] == "raytrace" and rays["rays"] == 160 * 120 and rays["hits"] > 0
    differing = np.any(traced != rasterized, axis=2).sum()
    assert differing < 160 * 120 / 500
    with pytest.raises(cuberille.InputError, match="--renderer: 'path' is not raster or raytrace"):
        scene.render(renderer="path", **settings)


def test_a_shadowed_frame_is_the_same_image_from_the_shadow_stages_visibility(examples):
    """frame_visibility="shadow-stage" shades the shadow stage's visibility buffer instead of
    drawing the scene again, "depth-test" draws it again: the same image, and the stats say which."""
    scene = cuberille.Scene(str(examples / "knot.obj"))
    settings = dict(width=160, height=120, ground=True, shadows="hybrid", ao=2)
    shaded = scene.render(frame_visibility="shadow-stage", **settings)
    assert scene.stats["frameVisibility"]["from"] == "shadow stage"
    assert scene.stats["frameVisibility"]["trianglesSeen"] > 0
    drawn = scene.render(frame_visibility="depth-test", **settings)
    assert scene.stats["frameVisibility"]["from"] == "depth test"
    assert np.array_equal(shaded, drawn)
    with pytest.raises(cuberille.InputError, match="--frame-visibility: 'maybe' is not auto, shadow-stage or depth-test"):
        scene.render(frame_visibility="maybe", **settings)


def test_linear_returns_the_renderers_floats(examples):
    scene = cuberille.Scene(examples / "torus.ply")
    linear = scene.render(64, 48, linear=True)
    assert linear.dtype == np.float32 and linear.shape == (48, 64, 4)
    assert np.all(linear[:, :, 3] == 1.0)  # an opaque background
    display = scene.render(64, 48)
    # Where the frame is black it is black in both; elsewhere the sRGB codes grow with the value.
    order = np.argsort(linear[:, :, 1], axis=None, kind="stable")
    assert np.all(np.diff(display[:, :, 1].ravel()[order].astype(int)) >= 0)


def test_stats_are_the_cli_stats(examples):
    scene = cuberille.Scene(examples / "knot.obj")
    scene.render(80, 60, msaa=4, threads=1)
    stats = scene.stats
    assert stats["width"] == 80 and stats["msaa"] == 4 and stats["threads"] == 1
    assert stats["sceneTriangles"] == 6144
    assert stats["stages"]["setup"]["setUp"] > 0


def test_the_thread_count_never_changes_the_image(examples):
    scene = cuberille.Scene(examples / "knot.obj")
    assert np.array_equal(scene.render(200, 150, msaa=4, threads=1), scene.render(200, 150, msaa=4, threads=2))


def test_animations_and_cameras_are_chosen_by_name_or_index(examples):
    scene = cuberille.Scene(examples / "spinning-box.gltf")
    assert len(scene.animations) == 1
    by_index = scene.render(64, 48, animation=0, time=1.0)
    by_name = scene.render(64, 48, animation=scene.animations[0] or "0", time=1.0)
    assert np.array_equal(by_index, by_name)
    assert not np.array_equal(by_index, scene.render(64, 48, animation=0, time=0.5))  # an eighth of a turn
    with pytest.raises(cuberille.InputError, match="no animation 'walk'"):
        scene.render(64, 48, animation="walk")
    assert scene.cameras == 0 and cuberille.Scene("demo").cameras == 0
    with pytest.raises(cuberille.InputError, match="--camera-index 0: .* has 0 camera"):
        scene.render(64, 48, camera_index=0)


def test_errors_carry_the_clis_messages(examples, cli, tmp_path):
    run = subprocess.run([cli, "render", str(examples / "torus.ply"), "--view", "sideways", "--out", str(tmp_path / "x.png")],
                         capture_output=True, text=True)
    assert run.returncode == 2
    with pytest.raises(cuberille.InputError) as raised:
        cuberille.render(examples / "torus.ply", view="sideways")
    assert str(raised.value) in run.stderr
    with pytest.raises(cuberille.InputError, match="cannot open file"):
        cuberille.Scene(tmp_path / "missing.glb")
    with pytest.raises(cuberille.InputError, match="--time: only glTF"):
        cuberille.render(examples / "torus.ply", time=1.0)
    with pytest.raises(ValueError):  # InputError is a ValueError
        cuberille.render("no-such-scene")
    with pytest.raises(TypeError, match="unexpected keyword argument 'colour'"):
        cuberille.render("demo", colour="red")


def test_rendering_releases_the_gil(examples):
    scene = cuberille.Scene("demo")
    worker = threading.Thread(target=lambda: scene.render(1280, 720, msaa=4, threads=1))
    worker.start()
    time.sleep(0.02)  # the worker is inside the native render by now (it takes far longer)
    ticks = 0
    while worker.is_alive():
        ticks += 1
        time.sleep(0.001)
    worker.join()
    assert ticks > 5, "the main thread did not run while the frame rendered: the GIL was held"


def test_assert_image_equal_passes_fails_and_updates(tmp_path, monkeypatch):
    monkeypatch.setenv("CUBERILLE_TEST_OUTPUT", str(tmp_path / "failed"))
    monkeypatch.delenv("CUBERILLE_UPDATE_GOLDEN", raising=False)
    image = cuberille.render("demo", 64, 36)
    golden = tmp_path / "golden" / "demo.png"
    with pytest.raises(AssertionError, match="no golden image"):
        testing.assert_image_equal(image, golden)
    monkeypatch.setenv("CUBERILLE_UPDATE_GOLDEN", "1")
    testing.assert_image_equal(image, golden)
    monkeypatch.delenv("CUBERILLE_UPDATE_GOLDEN")
    testing.assert_image_equal(image, golden)

    changed = image.copy()
    changed[10, 20, 0] ^= 0x40
    changed[11, 20, 1] = changed[11, 20, 1] // 2 + 1 if changed[11, 20, 1] > 2 else 200
    with pytest.raises(AssertionError) as failure:
        testing.assert_image_equal(changed, golden)
    message = str(failure.value)
    assert "2 pixels differ by more than 0" in message
    for suffix in ("actual", "golden", "difference", "compare"):
        written = tmp_path / "failed" / f"demo.{suffix}.png"
        assert written.exists() and str(written) in message
    assert np.array_equal(cuberille.read_png(str(tmp_path / "failed" / "demo.actual.png")), changed)
    testing.assert_image_equal(changed, golden, max_differing_pixels=2)
    with pytest.raises(AssertionError, match="is 32x36, the golden 64x36"):
        testing.assert_image_equal(image[:, :32], golden)


def test_the_readme_python_example_runs_as_written(examples, tmp_path, monkeypatch):
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    start = readme.index("```python\n", readme.index("From Python and C++")) + len("```python\n")
    code = readme[start:readme.index("```", start)]
    (tmp_path / "examples").symlink_to(examples)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    assert namespace["image"].shape == (480, 640, 4) and len(namespace["frames"]) == 3


def on_a_terminal(command):
    """Runs `command` with stderr on a pseudo-terminal: (the run, what the terminal showed)."""
    import os
    import pty
    controller, terminal = pty.openpty()
    try:
        run = subprocess.run(command, stdout=subprocess.PIPE, stderr=terminal, text=True,
                             env={**os.environ, "CUBERILLE_PROGRESS_AFTER_MS": "0"})
        os.close(terminal)
        shown = b""
        while True:
            try:
                chunk = os.read(controller, 4096)
            except OSError:  # the terminal's other end closed
                break
            if not chunk:
                break
            shown += chunk
    finally:
        os.close(controller)
    return run, shown


def test_long_work_shows_progress_on_a_terminal_only(cli, tmp_path):
    run, shown = on_a_terminal([cli, "render", "demo", "--turntable", "3", "--width", "64", "--height", "36",
                                "--out", str(tmp_path / "t.png")])
    assert run.returncode == 0
    assert b"frame 3 of 3" in shown and shown.endswith(b"\r\x1b[K"), shown
    assert "\r" not in run.stdout and run.stdout.startswith("wrote ")
    # One frame: its elapsed time (here from the start; by default after a second).
    run, shown = on_a_terminal([cli, "render", "field", "--width", "640", "--height", "360", "--out", str(tmp_path / "f.png")])
    assert run.returncode == 0
    assert b"rendering, " in shown and shown.endswith(b"\r\x1b[K"), shown
    assert "\r" not in run.stdout and run.stdout.startswith("wrote ")


def test_fly_streams_a_voxel_model_and_settles_on_the_cli_final_image(examples, cli, tmp_path):
    model = tmp_path / "torus.cvox"
    subprocess.run([cli, "voxelize", str(examples / "torus.ply"), "--resolution", "128", "-o", str(model), "--quiet"], check=True)
    result = cuberille.fly(model, "orbit", frames=6, width=160, height=120, msaa=1, budget_mib=4)
    assert len(result["frames"]) >= 6 and result["settled"]
    assert result["final_image"].shape == (120, 160, 4)
    image = result["final_image"]
    assert (image[:, :, :3] != image[0, 0, :3]).any(axis=2).sum() > 1000  # the torus, not the background
    out = tmp_path / "flight"
    subprocess.run([cli, "fly", str(model), "--path", "orbit", "--frames", "6", "--width", "160", "--height", "120",
                    "--msaa", "1", "--budget-mib", "4", "--out-dir", str(out), "--stats", str(tmp_path / "f.csv"),
                    "--quiet"], check=True)
    assert np.array_equal(result["final_image"], cuberille.read_png(str(out / "final.png")))
    # The settled frame's face figures are the CLI's last CSV row (the frames before it depend on
    # when the I/O thread's blocks arrived, in either run).
    with open(tmp_path / "f.csv", newline="") as f:
        last = list(csv.DictReader(f))[-1]
    settled = result["frames"][-1]
    for name in ("faces", "faces_between_samples", "faces_behind_depth", "covered_pixels"):
        assert settled[name] == int(last[name]), name
    assert settled["faces_per_covered_pixel"] == pytest.approx(float(last["faces_per_covered_pixel"]), abs=5e-4)
    assert settled["faces_between_samples"] > 0 and settled["covered_pixels"] > 1000
    for frame in result["frames"]:
        assert frame["faces_per_covered_pixel"] == pytest.approx(frame["faces"] / max(frame["covered_pixels"], 1))
    with pytest.raises(cuberille.InputError, match="fly needs a voxel model"):
        cuberille.fly(examples / "torus.ply")
