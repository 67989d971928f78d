"""Shared fixtures of the pytest examples (docs/python.md, "The examples").

CTest runs each file with PYTHONPATH=build/python and the variables below set. Run by hand
(``PYTHONPATH=build/python python3 -m pytest examples/python/``), each one unset is found in the
build tree the module comes from (or build/ of this repository); a test whose file is in neither
place is skipped with the variable's name."""

import os
import pathlib
from typing import Callable

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


def _build_dir() -> pathlib.Path:
    try:
        import dpc31
    except ImportError:
        return REPO / "build"
    return pathlib.Path(dpc31.__file__).resolve().parents[2]  # BUILD/python/dpc31/__init__.py


# Each variable and where the build puts what it names.
DEFAULTS = {
    "DPC31_CLI": "bin/dpc31",
    "DPC31_FW51": "firmware/mcs51",
    "DPC31_BOARD": "tests/mcs51/board",
    "DPC31_BAD_PLUGIN_HAL_INIT": "tests/libdpc31_bad_plugin_hal_init.so",
    "DPC31_BAD_PLUGIN_HAL_ISR": "tests/libdpc31_bad_plugin_hal_isr.so",
    "DPC31_BAD_PLUGIN_SPIN_INPUT": "tests/libdpc31_bad_plugin_spin_input.so",
}


def built_path(var: str) -> pathlib.Path:
    """The file or directory `var` names, else its place in the build tree; a skip if neither."""
    if var in os.environ:
        path = pathlib.Path(os.environ[var])
        if not path.exists():
            pytest.skip(f"{var}={path}: no such file")
        return path
    if var == "DPC31_TRACES":
        return REPO / "traces"
    path = _build_dir() / DEFAULTS[var]
    if not path.exists():
        pytest.skip(f"{var} not set, and the build has no {path} (build it, or set {var})")
    return path


@pytest.fixture
def built() -> Callable[[str], pathlib.Path]:
    return built_path


@pytest.fixture
def cli() -> str:
    """The dpc31 command line of the same build (the other door to the same chip)."""
    return str(built_path("DPC31_CLI"))


@pytest.fixture
def traces() -> pathlib.Path:
    return built_path("DPC31_TRACES")


def _refused_while(run, looks, hold):
    """The looks (name: callable) that this thread was refused while `run` ran in another, as
    {name: message}. `hold(callback)` adds an observer of that run (`hold(None)` removes it): its
    first call holds the run there, the GIL released, while this thread looks, so every look falls
    inside the run, whatever the scheduler does."""
    import threading

    import dpc31

    inside, looked = threading.Event(), threading.Event()

    def observer(*_):
        if not inside.is_set():
            inside.set()
            looked.wait()

    hold(observer)
    runner = threading.Thread(target=run)
    runner.start()
    refused = {}
    try:
        assert inside.wait(60), "the run called no observer"
        for name, look in looks.items():
            try:
                look()
            except dpc31.Error as e:
                refused[name] = str(e)
    finally:
        looked.set()
        runner.join()
    hold(None)
    return refused


@pytest.fixture
def refused_while():
    return _refused_while
