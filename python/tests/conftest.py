"""Shared fixtures of the quadrix pytest suite (run by ctest: python_test_*).

ctest sets PYTHONPATH to the module's build folder and QUADRIX_DATA_DIR, QUADRIX_SOURCE_DIR and
QUADRIX_EXECUTABLE (build/bin/quadrix); run by hand:
    PYTHONPATH=build/python /usr/bin/python3 -m pytest python/tests
"""
import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("QUADRIX_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


def _data_dir():
    """The shared real-data folder: $QUADRIX_DATA_DIR, else ../shared/data beside the checkout."""
    return pathlib.Path(os.environ.get("QUADRIX_DATA_DIR", SOURCE_DIR.parent / "shared" / "data"))


@pytest.fixture(scope="session")
def source_dir():
    """The repository's root folder."""
    return SOURCE_DIR


@pytest.fixture(scope="session")
def shared_data():
    """Returns a function mapping a path under the shared data folder to its Path, skipping the test
    with a message naming the file when it is absent."""

    def require(relative):
        path = _data_dir() / relative
        if not path.exists():
            pytest.skip(f"shared data absent: {path} (set QUADRIX_DATA_DIR)")
        return path

    return require


@pytest.fixture(scope="session")
def quadrix_cli():
    """Returns a function running build/bin/quadrix with arguments and returning its stdout; skips
    when the executable is not known (QUADRIX_EXECUTABLE unset and build/bin/quadrix missing)."""
    executable = pathlib.Path(os.environ.get("QUADRIX_EXECUTABLE", SOURCE_DIR / "build" / "bin" / "quadrix"))
    if not executable.exists():
        pytest.skip(f"quadrix executable not found: {executable} (set QUADRIX_EXECUTABLE)")

    def run(*arguments):
        completed = subprocess.run([str(executable), *map(str, arguments)], capture_output=True, text=True)
        assert completed.returncode == 0, completed.stderr
        return completed.stdout

    return run


@pytest.fixture(scope="session")
def street():
    """The simulated street pair of `make demo` (quadrix synth street --seed 3 --sensor hdl64)."""
    import quadrix

    return quadrix.synth("street", seed=3, sensor="hdl64", primitives=False)
