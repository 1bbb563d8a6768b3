"""Shared fixtures: the repository root, the arm of examples/arm7.urdf, the module's folder;
helpers for the tests that compare states bit for bit."""
import os
import pathlib
import re

import numpy as np
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


def driven(model, solver="tgs"):
    """A simulation of model with stiff drives towards fixed targets (dt 0.01)."""
    sim = fd.Simulation(model, dt=0.01, solver=solver)
    sim.set_drive_gains(np.full(model.nv, 900.0), np.full(model.nv, 25.0))
    sim.set_drive_targets(np.linspace(-0.5, 0.5, model.nv), np.full(model.nv, 0.2))
    return sim


def hexes(a):
    """Every value of a as float.hex(): equal lists mean bit-identical arrays."""
    return [float(x).hex() for x in np.asarray(a).ravel()]


def in_lanes(path):
    """Whether a Batch's step_path says one lane group ("avx2 lanes"), in one-lane blocks too
    ("sse2 lanes (3 at one lane)": FEATHERDRIVE_SIMD=one steps every group so)."""
    return re.fullmatch(r"(sse2|avx2|avx512) lanes( \(\d+ at one lane\))?", path) is not None
