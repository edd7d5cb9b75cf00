"""Shared fixtures: the fetched data folder and the voxfx command of the same build.

ctest sets PYTHONPATH (the build tree's python/ folder), VOXFX_CLI_PATH and VOXFX_DATA_DIR_DEFAULT;
VOXFX_DATA_DIR overrides the data folder as in the C++ tests. A missing data file skips its test,
or fails it when VOXFX_REQUIRE_DATA is set (CI, after fetching the data).
"""
import os
import shutil

import pytest


def _data_dir():
    for var in ("VOXFX_DATA_DIR", "VOXFX_DATA_DIR_DEFAULT"):
        if os.environ.get(var):
            return os.environ[var]
    return os.path.join(os.path.dirname(__file__), "..", "..", "data")


@pytest.fixture(scope="session")
def data_path():
    def path(relative):
        p = os.path.abspath(os.path.join(_data_dir(), relative))
        if not os.path.exists(p):
            message = "missing test data " + p + " (run scripts/fetch-data.sh)"
            if os.environ.get("VOXFX_REQUIRE_DATA", "0") not in ("", "0"):
                pytest.fail(message)
            pytest.skip(message)
        return p

    return path


@pytest.fixture(scope="session")
def cli():
    p = os.environ.get("VOXFX_CLI_PATH") or shutil.which("voxfx")
    if not p or not os.path.exists(p):
        pytest.skip("the voxfx command is not built (set VOXFX_CLI_PATH)")
    return p
