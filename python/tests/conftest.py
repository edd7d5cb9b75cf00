"""Shared fixtures: the fetched data folder, the voxfx command of the same build, and a probe of
whether a call releases the GIL.

ctest sets PYTHONPATH (the build tree's python/ folder), VOXFX_CLI_PATH and VOXFX_DATA_DIR_DEFAULT;
VOXFX_DATA_DIR overrides the data folder as in the C++ tests. A missing data file skips its test,
or fails it when VOXFX_REQUIRE_DATA is set (CI, after fetching the data).
"""
import os
import shutil
import threading
import time

import pytest


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: a long case, run by the ctest test python.pytest.slow (label slow)")


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


@pytest.fixture(scope="session")
def gil_stall():
    """gil_stall(call) runs call() while a Python thread takes timestamps and returns the call's
    duration and the longest gap between timestamps within it: with the GIL held for the whole
    call the gap is most of the call (around its start and end the interpreter may switch threads
    either way). The call should use one thread, so that a core stays free for the counter. Of up
    to three tries, the one with the smallest gap for its duration counts: a machine busy with other
    work (ctest -j beside other jobs) can keep the counter off the CPU for part of one call, while
    with the GIL held every try stalls."""
    def once(call):
        stamps = []
        stop = threading.Event()

        def count():
            while not stop.is_set():
                stamps.append(time.perf_counter())

        t = threading.Thread(target=count)
        t.start()
        while not stamps:
            time.sleep(0.001)
        t0 = time.perf_counter()
        call()
        t1 = time.perf_counter()
        stop.set()
        t.join()
        inside = [t0] + [s for s in stamps if t0 < s < t1] + [t1]
        return t1 - t0, max(b - a for a, b in zip(inside, inside[1:]))

    def run(call):
        best = None
        for _ in range(3):
            duration, gap = once(call)
            if best is None or gap / duration < best[1] / best[0]:
                best = (duration, gap)
            if gap < 0.25 * duration:
                break
        return best

    return run
