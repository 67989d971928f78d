"""Shared fixtures of the pytest examples (docs/python.md). CTest runs each file with
PYTHONPATH=build/python, DPC31_CLI=build/bin/dpc31 and DPC31_TRACES=traces/."""

import os
import pathlib

import pytest


@pytest.fixture
def cli() -> str:
    """The dpc31 command line of the same build (the other door to the same chip)."""
    return os.environ["DPC31_CLI"]


@pytest.fixture
def traces() -> pathlib.Path:
    return pathlib.Path(os.environ["DPC31_TRACES"])
