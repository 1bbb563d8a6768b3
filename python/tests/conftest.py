"""Shared fixtures: the repository root, the arm of examples/arm7.urdf, the module's folder."""
import os
import pathlib

import pytest

import featherdrive as fd

ROOT = pathlib.Path(__file__).resolve().parents[2]
ARM = ROOT / "examples" / "arm7.urdf"


@pytest.fixture(scope="session")
def arm():
    """The 7-dof arm's Model (fixed base)."""
    return fd.load_urdf(str(ARM)).model


@pytest.fixture(scope="session")
def module_dir():
    """The folder the module was loaded from (build/python), which also holds
    python_parity_reference."""
    return pathlib.Path(os.path.dirname(fd.__file__))
