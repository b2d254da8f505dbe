"""Fixtures for the module's tests: the example inputs (examples/make_examples.py) written into a
temporary folder once per session, and the command-line tool to compare against."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPOSITORY = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def examples(tmp_path_factory):
    folder = tmp_path_factory.mktemp("examples")
    subprocess.run([sys.executable, str(REPOSITORY / "examples" / "make_examples.py"), str(folder)], check=True,
                   stdout=subprocess.DEVNULL)
    return folder


@pytest.fixture(scope="session")
def cli():
    binary = os.environ.get("CUBERILLE_BINARY")
    if not binary:
        pytest.skip("CUBERILLE_BINARY is not set (ctest sets it to the built tool)")
    return binary
