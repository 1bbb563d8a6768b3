"""A step from Python equals the same step from C++ bit for bit: python_parity_reference (built
next to the module) steps a fixed scenario on the arm from C++ and prints q, qd, drive_force and
limit_force as %a hex floats; the same scenario set up here through the module must give the same
doubles. The scenario is described in python/parity_reference.cpp."""
import subprocess

import numpy as np
import pytest

import featherdrive as fd
from conftest import ARM

STEPS = 40


def reference(module_dir, solver):
    exe = module_dir / "python_parity_reference"
    run = subprocess.run([str(exe), str(ARM), solver, str(STEPS)], capture_output=True, text=True,
                         timeout=120, check=True)
    out = {}
    for line in run.stdout.splitlines():
        name, *values = line.split()
        out[name] = [float.fromhex(v) for v in values]
    return out


def python_side(model, solver, stepping):
    sim = fd.Simulation(model, dt=1.0 / 60.0, solver=solver, position_iterations=4,
                        velocity_iterations=1)
    nv = model.nv
    d = np.arange(nv)
    q = np.array(sim.q)
    for k in range(nv):
        q[model.links[model.dof_link[k]].q_index] = 0.1 * (k + 1)
    sim.set_q(q)
    sim.set_qd(np.array([-0.05 * k for k in range(nv)]))
    sim.set_drive_gains(np.array([1000.0 * (k + 1) for k in range(nv)]),
                        np.array([50.0 + 10.0 * k for k in range(nv)]))
    sim.set_drive_targets(np.array([0.5 - 0.1 * k for k in range(nv)]), np.full(nv, 0.2))
    assert d.size == nv
    stepping(sim)
    return sim


def hexes(values):
    return [float(v).hex() for v in values]


@pytest.mark.parametrize("solver", ["pgs", "tgs"])
@pytest.mark.parametrize("stepping", ["one_call", "one_by_one"])
def test_python_step_equals_cpp_step(arm, module_dir, solver, stepping):
    ref = reference(module_dir, solver)
    if stepping == "one_call":
        sim = python_side(arm, solver, lambda s: s.step(STEPS))
    else:
        sim = python_side(arm, solver, lambda s: [s.step() for _ in range(STEPS)])
    assert sim.step_count == STEPS
    for name in ("q", "qd", "drive_force", "limit_force"):
        got = getattr(sim, name)
        assert got.dtype == np.float64
        assert hexes(got) == [v.hex() for v in ref[name]], name
    # The scenario must do something: the arm moved and the drives pushed.
    assert np.any(np.abs(sim.qd) > 1e-3)
    assert np.any(np.abs(sim.drive_force) > 1.0)
