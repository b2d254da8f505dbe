"""A golden-image test as a user of the Python module writes one (docs/library.md): render a glTF
model at a few moments of its animation and compare each frame with an approved PNG.

    PYTHONPATH=build/release/python python3 -m pytest examples/test_spinning_box.py

Run once with CUBERILLE_UPDATE_GOLDEN=1 to write the goldens, review them, commit them. The
model is made by examples/make_examples.py (`make examples`); here it is written into a
temporary folder so the test runs on a fresh clone.
"""

import subprocess
import sys
from pathlib import Path

import pytest

import cuberille
from cuberille.testing import assert_image_equal

HERE = Path(__file__).resolve().parent


@pytest.fixture(scope="module")
def spinning_box(tmp_path_factory):
    folder = tmp_path_factory.mktemp("models")
    subprocess.run([sys.executable, str(HERE / "make_examples.py"), str(folder)], check=True, stdout=subprocess.DEVNULL)
    return cuberille.Scene(folder / "spinning-box.gltf")  # loaded once for every frame below


@pytest.mark.parametrize("seconds", [0.0, 1.0, 2.5])
def test_spinning_box_matches_its_golden(spinning_box, seconds):
    image = spinning_box.render(320, 240, msaa=4, time=seconds, shadows="hybrid")
    assert_image_equal(image, HERE / "golden" / f"spinning-box-{seconds:g}s.png")
