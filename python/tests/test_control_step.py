"""Control steps from Python: hold is set_drive_targets then step(k); linear follows the closed form
prev + j/k (new - prev) computed here in numpy; a Batch broadcasts scalar, (nv,) and (N, nv)
targets and equals separate simulations; bad arguments raise ValueError / TypeError."""
import numpy as np
import pytest

import featherdrive as fd

from conftest import ROOT, driven, hexes


def test_hold_is_set_targets_then_k_steps(arm):
    for solver in ("pgs", "tgs"):
        control, manual = driven(arm, solver), driven(arm, solver)
        p, v = np.linspace(0.4, -0.3, arm.nv), np.full(arm.nv, -0.1)
        control.step_control(p, v, substeps=5)
        manual.set_drive_targets(p, v)
        manual.step(5)
        assert hexes(control.q) == hexes(manual.q) and hexes(control.qd) == hexes(manual.qd)
        assert control.step_count == 5


def test_linear_follows_the_closed_form_step_by_step(arm):
    control, manual = driven(arm), driven(arm)
    prev_p, prev_v = np.linspace(-0.5, 0.5, arm.nv), np.full(arm.nv, 0.2)  # driven()'s targets
    k = 4
    for call, new_p in enumerate((np.full(arm.nv, 0.7), np.linspace(0.1, -0.6, arm.nv))):
        new_v = np.full(arm.nv, 0.3 * call)
        control.step_control(new_p, new_v, substeps=k, targets="linear")
        for j in range(1, k + 1):
            # The closed form, in the same float64 operations; sub-step k takes the new targets.
            p = new_p if j == k else prev_p + (j / k) * (new_p - prev_p)
            v = new_v if j == k else prev_v + (j / k) * (new_v - prev_v)
            manual.set_drive_targets(p, v)
            manual.step()
        assert hexes(control.q) == hexes(manual.q), call
        assert hexes(control.drive_force) == hexes(manual.drive_force), call
        prev_p, prev_v = new_p, new_v
    # Linear differs from hold: the interpolation is not a no-op.
    held = driven(arm)
    held.step_control(np.full(arm.nv, 0.7), 0.0, substeps=k)
    other = driven(arm)
    other.step_control(np.full(arm.nv, 0.7), 0.0, substeps=k, targets="linear")
    assert hexes(held.q) != hexes(other.q)


def test_batch_broadcasts_and_equals_separate_simulations(arm):
    n = 3
    rows = np.linspace(-0.4, 0.4, n)[:, None] + np.linspace(0.0, 0.2, arm.nv)[None, :]
    for targets, per_copy in ((0.25, lambda i: np.full(arm.nv, 0.25)),
                              (rows[0], lambda i: rows[0]),
                              (rows, lambda i: rows[i])):
        batch = fd.Batch(driven(arm), n)
        batch.step_control(targets, 0.1, substeps=3, targets="linear")
        for i in range(n):
            alone = driven(arm)
            alone.step_control(per_copy(i), np.full(arm.nv, 0.1), substeps=3, targets="linear")
            # SIMD lanes: within 1e-12 of the lone step (another operation order).
            assert np.max(np.abs(batch.q[i] - alone.q)) <= 1e-12, i
            assert batch.sim(i).step_count == 3


def test_bad_arguments(arm):
    sim = driven(arm)
    with pytest.raises(ValueError, match=r"step_control: substeps = 0 is out of range"):
        sim.step_control(0.0, substeps=0)
    with pytest.raises(TypeError, match="step_control: substeps"):
        sim.step_control(0.0, substeps=2.0)
    with pytest.raises(ValueError,
                       match="step_control: targets = 'cubic': must be 'hold' or 'linear'"):
        sim.step_control(0.0, targets="cubic")
    with pytest.raises(TypeError, match="step_control: targets must be a str"):
        sim.step_control(0.0, targets=1)
    with pytest.raises(ValueError, match=r"step_control: target_position has shape \(3,\)"):
        sim.step_control(np.zeros(3))
    with pytest.raises(ValueError, match="step_control: target_velocity of dof 2 .* is not finite"):
        sim.step_control(0.0, np.where(np.arange(arm.nv) == 2, np.nan, 0.0))
    batch = fd.Batch(arm, 2)
    with pytest.raises(ValueError, match=r"step_control: target_position has shape \(3, 7\)"):
        batch.step_control(np.zeros((3, 7)))
    assert sim.step_count == 0 and batch.sim(0).step_count == 0


def test_divergence_names_the_substep():
    slider = fd.load_urdf(str(ROOT / "examples" / "slider.urdf")).model  # 2.5 kg

    def runaway():
        sim = fd.Simulation(slider, dt=1.0)
        sim.set_joint_limits("slide", -np.inf, np.inf)
        sim.set_max_joint_velocity("slide", np.inf)
        sim.set_applied_force(np.full(slider.nv, 2.5e307))
        return sim

    plain, sim = runaway(), runaway()
    made = 0
    with pytest.raises(fd.DivergenceError):
        for made in range(10):
            plain.step()
    assert 1 <= made < 10  # the step where a plain simulation diverges
    with pytest.raises(fd.DivergenceError, match=f"^step_control: sub-step {made + 1} of 10: "):
        sim.step_control(0.0, substeps=10)
    assert sim.step_count == made and hexes(sim.q) == hexes(plain.q)
