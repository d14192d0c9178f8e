"""Shared fixtures: the command-line binary and the committed test data (ctest sets both; from a
shell, run with PYTHONPATH=build/python from the repository)."""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def clogscope_binary():
    path = pathlib.Path(os.environ.get("CLOGSCOPE_BINARY", REPO / "build" / "bin" / "clogscope"))
    assert path.exists(), f"{path}: build the command line first"
    return path


@pytest.fixture(scope="session")
def testdata():
    return pathlib.Path(os.environ.get("CLOGSCOPE_TESTDATA_DIR", REPO / "testdata"))


@pytest.fixture(scope="session")
def run_cli(clogscope_binary):
    """Runs `clogscope ARGS...` (a list: no shell) and returns the completed process."""

    def run(*args, check=True):
        proc = subprocess.run([str(clogscope_binary), *map(str, args)], capture_output=True,
                              text=True, env={**os.environ, "CLOGSCOPE_LOG": "warn"})
        if check and proc.returncode != 0:
            raise AssertionError(f"clogscope {' '.join(map(str, args))}: exit "
                                 f"{proc.returncode}\n{proc.stderr}")
        return proc

    return run


def data_lines(text):
    """The CSV's lines after its leading '#' comments (provenance differs between runs)."""
    return [line for line in text.splitlines() if not line.startswith("#")]
