"""Cuberille: a deterministic CPU renderer, from Python.

    import cuberille
    image = cuberille.render("model.glb", width=640, height=480, msaa=4)   # (480, 640, 4) uint8, sRGB

The array holds exactly the pixels `cuberille render --out x.png` writes for the same options
(alpha 255 where the PNG has no alpha channel). Keyword options are the command line's render
options by their names with underscores (`--pixel-error` is `pixel_error`); see docs/library.md.
A Scene loads a file once and renders it many times. Rendering releases the GIL.
"""

import json
import os

from ._cuberille import InputError, read_png, write_png
from . import _cuberille

__all__ = ["InputError", "Scene", "fly", "render", "read_png", "write_png"]


class Scene:
    """A scene loaded once: a .tri, .ply, .ply.gz, .obj, .gltf, .glb or .cvox file, or a built-in
    scene's name. `detail` scales built-in scenes' tessellation; `up_axis="z"` turns a mesh file
    whose up is +z to +y. Raises InputError for bad input, with the command line's message."""

    def __init__(self, path, *, detail=1.0, up_axis="y"):
        self._scene = _cuberille.Scene(os.fspath(path), float(detail), up_axis)
        self.stats = None

    def render(self, width=1280, height=720, msaa=1, *, linear=False, **options):
        """One frame as a (height, width, 4) array: uint8 sRGB, or with linear=True float32
        linear RGBA (colour premultiplied by alpha; for view="depth", distances from the eye).
        Options: threads, view, azimuth, elevation, camera_index, eye, target, up, fov, orbit,
        time, animation, zoom, orthographic, shadows, soft, light_radius, shadow_map_size, soft_samples,
        shadow_focus (view, the default for one frame, or scene: a sun's map kept across views),
        ao (ambient occlusion: rays a pixel), ao_distance (their reach; 0: a tenth of the model),
        environment ("neutral" or an equirectangular .hdr radiance map), environment_intensity, frustum_cull, ground, shadow_catcher, bvh_update, accel, renderer,
        frame_visibility (a shadowed raster frame: "auto", "shadow-stage" or "depth-test"; the same image), supersample, texture_filter, depth, background, legend, pixel_error,
        voxel_resolution, no_hybrid, no_occlusion, warmup. Afterwards `stats` holds the frame's
        statistics as `--stats` writes them."""
        image = self._scene.render(width, height, msaa, linear, **options)
        self.stats = json.loads(self._scene.stats_json)
        return image

    @property
    def name(self):
        return self._scene.name

    @property
    def animations(self):
        """A glTF's animations' names in file order (an index in this list also selects one)."""
        return list(self._scene.animations)

    @property
    def cameras(self):
        """How many cameras a glTF has (render(camera_index=i) looks through one); 0 for others."""
        return self._scene.cameras

    @property
    def warnings(self):
        """What the loader warned about (unsupported extensions and the like), in order."""
        return list(self._scene.warnings)


def render(path, width=1280, height=720, msaa=1, *, detail=1.0, up_axis="y", **options):
    """Loads `path` and renders one frame: Scene(path).render(width, height, msaa, **options)."""
    return Scene(path, detail=detail, up_axis=up_axis).render(width, height, msaa, **options)


def fly(model, path="orbit", frames=120, width=1280, height=720, msaa=4, *, threads=0, budget_mib=1024.0,
        upload_limit_mib=0.0, refine="full", pixel_error=1.0, settle_frames=1000):
    """A flight through a voxel model (.cvox) streamed under `budget_mib` along `path` (orbit, zoom
    or a keyframe file), as `cuberille fly` runs it. Returns a dict: "frames" (a dict of times and
    counts per frame, the settling frames after the path's), "final_image" (the settled last view,
    uint8 sRGB RGBA), "settled", "bytes_read_from_disk", "peak_held_bytes", "budget_bytes",
    "open_ms", "warnings". Releases the GIL while it flies."""
    return _cuberille.fly(os.fspath(model), os.fspath(path) if path not in ("orbit", "zoom") else path, int(frames),
                          int(width), int(height), int(msaa), int(threads), float(budget_mib), float(upload_limit_mib),
                          refine, float(pixel_error), int(settle_frames))
