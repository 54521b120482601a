"""Paths the tests need, from the environment the test command sets (test/CMakeLists.txt)."""
import os
import pathlib

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("SPINNING_TOP_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


@pytest.fixture(scope="session")
def source_dir():
    return SOURCE_DIR


@pytest.fixture(scope="session")
def simulate():
    path = os.environ.get("SPINNING_TOP_SIMULATE")
    if not path or not os.access(path, os.X_OK):
        pytest.fail("SPINNING_TOP_SIMULATE must name the built simulate executable")
    return path
