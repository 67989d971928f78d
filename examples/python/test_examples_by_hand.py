"""The examples run by hand as docs/python.md says, without CTest's variables
(``PYTHONPATH=build/python python3 -m pytest examples/python/``): conftest.py finds what each
variable names in the build tree the module comes from, and skips a test whose file is not there
with the variable's name, instead of stopping at collection with a KeyError."""

import os
import pathlib
import subprocess
import sys

import dpc31

HERE = pathlib.Path(__file__).resolve().parent
VARIABLES = ("DPC31_CLI", "DPC31_TRACES", "DPC31_FW51", "DPC31_BOARD",
             "DPC31_BAD_PLUGIN_HAL_INIT", "DPC31_BAD_PLUGIN_HAL_ISR")


def pytest_run(test, **env):
    clean = {k: v for k, v in os.environ.items() if k not in VARIABLES}
    clean["PYTHONPATH"] = str(pathlib.Path(dpc31.__file__).resolve().parents[1])
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider",
         str(HERE / test)], env=dict(clean, **env), cwd=HERE.parents[1],
        capture_output=True, text=True)


def test_without_the_variables_the_build_tree_is_found():
    run = pytest_run("test_cpu51.py::test_the_c31_runs_from_the_chips_ram")
    assert run.returncode == 0, run.stdout + run.stderr
    assert "1 passed" in run.stdout


def test_a_file_in_neither_place_skips_with_the_variables_name(tmp_path):
    missing = tmp_path / "nowhere"
    run = pytest_run("test_cpu51.py::test_the_c31_runs_from_the_chips_ram",
                     DPC31_BOARD=str(missing))
    assert run.returncode == 0, run.stdout + run.stderr
    assert f"DPC31_BOARD={missing}: no such file" in run.stdout and "1 skipped" in run.stdout
