"""Checkpoints from Python: a run interrupted, saved, restored into a fresh simulation and resumed
equals the uninterrupted run bit for bit; a truncated file is refused."""
import pathlib

import numpy as np
import pytest

import featherdrive as fd

ARM = pathlib.Path(__file__).resolve().parents[2] / "examples" / "arm7.urdf"


def make_sim(model):
    sim = fd.Simulation(model, fd.SimulationOptions(dt=1.0 / 60, solver="tgs",
                                                    position_iterations=4, velocity_iterations=1))
    for j in range(model.nv):
        sim.set_drive(j, fd.Drive(type="force", stiffness=2e4, damping=300,
                                  target_position=0.3 * np.sin(j), target_velocity=0.1))
    return sim


def test_resumed_run_equals_uninterrupted(tmp_path):
    model = fd.load_urdf(str(ARM)).model
    whole = make_sim(model)
    whole.step(60)
    first = make_sim(model)
    first.step(25)
    fd.save_checkpoint(first, tmp_path / "state.bin")
    resumed = make_sim(model)
    fd.load_checkpoint(tmp_path / "state.bin", resumed)
    resumed.step(35)
    assert [x.hex() for x in resumed.q] == [x.hex() for x in whole.q]
    assert [x.hex() for x in resumed.qd] == [x.hex() for x in whole.qd]
    assert [x.hex() for x in resumed.drive_force] == [x.hex() for x in whole.drive_force]


def test_truncated_checkpoint_is_refused(tmp_path):
    model = fd.load_urdf(str(ARM)).model
    sim = make_sim(model)
    sim.step(3)
    path = tmp_path / "state.bin"
    fd.save_checkpoint(sim, path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    before = np.array(sim.q)
    with pytest.raises(ValueError, match="truncated"):
        fd.load_checkpoint(path, sim)
    assert np.array_equal(np.array(sim.q), before)
