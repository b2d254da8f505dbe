"""Golden-image assertions for tests (pytest or unittest).

    from cuberille.testing import assert_image_equal
    assert_image_equal(cuberille.render("model.glb", 320, 240), "golden/model.png")

With CUBERILLE_UPDATE_GOLDEN=1 in the environment the golden is (re)written from the image
instead of compared. On a failure the image, the golden and a picture of where they differ are
written side by side into CUBERILLE_TEST_OUTPUT (default: a `cuberille-failed` folder in the
system's temporary folder) and the message names them.
"""

import os
import tempfile
from pathlib import Path

import numpy as np

from ._cuberille import read_png, write_png

__all__ = ["assert_image_equal", "update_goldens"]


def update_goldens():
    """Whether this run rewrites goldens instead of comparing (CUBERILLE_UPDATE_GOLDEN=1)."""
    return os.environ.get("CUBERILLE_UPDATE_GOLDEN", "") not in ("", "0")


def _as_rgba8(image):
    a = np.asarray(image)
    if a.dtype != np.uint8 or a.ndim != 3 or a.shape[2] not in (3, 4):
        raise TypeError(f"expected a (height, width, 3 or 4) uint8 array, got {a.dtype} of shape {a.shape}")
    if a.shape[2] == 3:
        a = np.concatenate([a, np.full(a.shape[:2] + (1,), 255, np.uint8)], axis=2)
    return np.ascontiguousarray(a)


def _failure_folder():
    folder = Path(os.environ.get("CUBERILLE_TEST_OUTPUT") or Path(tempfile.gettempdir()) / "cuberille-failed")
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def _difference_picture(actual, expected, tolerance):
    """Grey where the images agree (the golden, dimmed), red where a channel differs by more than
    the tolerance, brighter the larger the difference."""
    difference = np.abs(actual.astype(np.int16) - expected.astype(np.int16)).max(axis=2)
    picture = (expected[:, :, :3] // 4).astype(np.uint8)
    differs = difference > tolerance
    picture[differs] = 0
    picture[differs, 0] = np.clip(128 + difference[differs], 0, 255).astype(np.uint8)
    return picture


def assert_image_equal(image, golden_png, max_differing_pixels=0, tolerance=0):
    """Asserts that `image` (a uint8 array as cuberille.render returns) matches the PNG
    `golden_png`: at most `max_differing_pixels` pixels may have a channel that differs by more
    than `tolerance` (in 8-bit codes). Raises AssertionError naming the pictures it wrote."""
    actual = _as_rgba8(image)
    golden = Path(golden_png)
    if update_goldens():
        golden.parent.mkdir(parents=True, exist_ok=True)
        write_png(str(golden), actual)
        return
    if not golden.exists():
        raise AssertionError(f"{golden}: no golden image; run with CUBERILLE_UPDATE_GOLDEN=1 to write it from this image")
    expected = read_png(str(golden))
    stem = golden.stem
    folder = _failure_folder()
    written = {"image": folder / f"{stem}.actual.png", "golden": folder / f"{stem}.golden.png"}
    if actual.shape != expected.shape:
        write_png(str(written["image"]), actual)
        write_png(str(written["golden"]), expected)
        raise AssertionError(f"{golden}: the image is {actual.shape[1]}x{actual.shape[0]}, the golden "
                             f"{expected.shape[1]}x{expected.shape[0]}; wrote {written['image']} and {written['golden']}")
    differing = int((np.abs(actual.astype(np.int16) - expected.astype(np.int16)).max(axis=2) > tolerance).sum())
    if differing <= max_differing_pixels:
        return
    written["difference"] = folder / f"{stem}.difference.png"
    written["side by side"] = folder / f"{stem}.compare.png"
    picture = _difference_picture(actual, expected, tolerance)
    write_png(str(written["image"]), actual)
    write_png(str(written["golden"]), expected)
    write_png(str(written["difference"]), picture)
    opaque = np.concatenate([actual[:, :, :3], expected[:, :, :3], picture], axis=1)
    write_png(str(written["side by side"]), np.ascontiguousarray(opaque))
    listing = "\n".join(f"  {what}: {path}" for what, path in written.items())
    raise AssertionError(f"{golden}: {differing} pixels differ by more than {tolerance} "
                         f"(at most {max_differing_pixels} allowed); wrote\n{listing}\n"
                         "Run with CUBERILLE_UPDATE_GOLDEN=1 to accept the new image.")
