"""Drive delays from Python: the delayed response is the undelayed one K steps later (the step is
time-invariant), Batch environments equal lone Simulations, checkpoints keep the pending targets,
scenes and bad values."""
import numpy as np
import pytest

import featherdrive as fd
from conftest import ROOT, hexes, in_lanes


def chain(model, delay):
    sim = fd.Simulation(model, dt=0.01, solver="tgs")
    sim.set_drive_gains(np.full(model.nv, 400.0), np.full(model.nv, 30.0))
    for j in range(model.nv):
        sim.set_drive_delay(j, delay)
    return sim


def targets(k, nv):
    return np.zeros(nv) if k < 4 else 0.3 * np.sin(0.2 * k + np.arange(nv))


def test_delay_shifts_the_response_by_k_steps_bit_for_bit():
    # No gravity: at rest at its zero targets the chain stays still, so the delayed run's first
    # steps are the undelayed run's rest.
    model = fd.parse_scene("model: chain3.urdf\nsteps: 1\ngravity: [0, 0, 0]\n",
                           str(ROOT / "examples" / "inline.yaml")).model
    plain, delayed = chain(model, 0), chain(model, 3)
    qs_plain, qs_delayed = [], []
    for k in range(40):
        for s, out in ((plain, qs_plain), (delayed, qs_delayed)):
            s.set_drive_targets(targets(k, model.nv))
            s.step()
            out.append(np.array(s.q))
    assert np.abs(qs_plain[-1]).max() > 0.05
    for n in range(37):
        assert hexes(qs_delayed[n + 3]) == hexes(qs_plain[n]), n
    assert delayed.drive_delay("joint2") == 3
    assert delayed.drive(1).target_position == targets(39, model.nv)[1]  # as commanded


@pytest.mark.parametrize("lanes", [False, True])
def test_batch_environments_equal_simulations_and_checkpoints_resume(arm, tmp_path, lanes):
    """Without SIMD lanes each environment is its Simulation bit for bit; in them (the delays a
    control stage before the lane step) within 1e-12, another operation order."""
    proto = fd.Simulation(arm, dt=0.01)
    proto.set_drive_gains(np.full(arm.nv, 900.0), np.full(arm.nv, 40.0))
    batch = fd.Batch(proto, 3)
    batch.lanes = lanes
    delays = np.array([[0] * 7, [1, 2, 3, 4, 5, 6, 7], [2] * 7])
    batch.set_drive_delay(delays[1:], env_ids=[1, 2])
    assert np.array_equal(batch.drive_delay(), delays)
    sims = [fd.Simulation(arm, dt=0.01) for _ in range(3)]
    for i, s in enumerate(sims):
        s.set_drive_gains(np.full(arm.nv, 900.0), np.full(arm.nv, 40.0))
        for j in range(7):
            s.set_drive_delay(j, int(delays[i, j]))
    for k in range(12):
        x = 0.4 * np.sin(0.3 * k + np.arange(7))
        batch.set_drive_targets(x)
        batch.step()
        for s in sims:
            s.set_drive_targets(x)
            s.step()
    assert in_lanes(batch.step_path) == lanes, batch.step_path
    for i, s in enumerate(sims):
        if lanes:
            assert np.abs(batch.q[i] - s.q).max() <= 1e-12, i
        else:
            assert hexes(batch.q[i]) == hexes(s.q), i
        assert [batch.sim(i).drive_delay(j) for j in range(7)] == list(delays[i])
    # A checkpoint mid-delay resumes bit for bit.
    path = tmp_path / "mid.ckpt"
    fd.save_checkpoint(sims[1], str(path))
    resumed = fd.Simulation(arm, dt=0.01)
    fd.load_checkpoint(str(path), resumed)
    assert resumed.drive_delay(6) == 7
    for s in (sims[1], resumed):
        for k in range(12, 20):
            s.set_drive_targets(0.4 * np.sin(0.3 * k + np.arange(7)))
            s.step()
    assert hexes(resumed.q) == hexes(sims[1].q)


def test_scene_delay_and_bad_values(arm):
    scene = fd.parse_scene("model: arm7.urdf\nsteps: 1\n"
                           "drive_defaults: {type: force, stiffness: 10, delay: 2}\n",
                           str(ROOT / "examples" / "inline.yaml"))
    assert [d.delay for d in scene.drives] == [2] * 7
    assert fd.make_simulation(scene).drive_delay("joint7") == 2
    sim = fd.Simulation(arm)
    with pytest.raises(ValueError, match=r"joint 'joint1' \(dof 0\) has no drive"):
        sim.set_drive_delay("joint1", 2)
    sim.set_drive_gains(np.full(7, 10.0), np.full(7, 1.0))
    with pytest.raises(ValueError, match=r"delay = -1 must be in \[0, 100000\] steps"):
        sim.set_drive_delay(0, -1)
    with pytest.raises(TypeError):
        sim.set_drive_delay(0, 2.5)
    batch = fd.Batch(sim, 2)
    with pytest.raises(ValueError, match=r"environment 0: drive delay of joint 'joint1' = 1.5 "
                                         r"must be a whole number"):
        batch.set_drive_delay(1.5)
    assert not batch.drive_delay().any()


def test_batch_drive_delay_is_all_or_nothing(arm):
    """Delays whose histories would exceed the batch's bound (2**26 samples) are refused before
    any environment changes: ValueError, every environment's delays as they were."""
    sim = fd.Simulation(arm)
    sim.set_drive_gains(np.full(7, 10.0), np.full(7, 1.0))
    batch = fd.Batch(sim, 1000)
    batch.set_drive_delay(4, env_ids=[7])
    samples = 1000 * 7 * 100001
    with pytest.raises(ValueError, match=f"need {samples} samples.*nothing changed"):
        batch.set_drive_delay(100000)
    expected = np.zeros((1000, 7))
    expected[7] = 4
    assert np.array_equal(batch.drive_delay(), expected)
    # Within the bound: every environment takes it.
    batch.set_drive_delay(9)
    assert np.array_equal(batch.drive_delay(), np.full((1000, 7), 9.0))
