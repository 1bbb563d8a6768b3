"""The step guard from Python (docs/math/step_guard.md): options.guard, the counters, a scene's
guard: key, bit for bit the unguarded step where it does not trigger, bad bounds one ValueError
naming the key and value."""
import numpy as np
import pytest

import featherdrive as fd

from conftest import ROOT, hexes


def slider_sim(guard):
    model = fd.load_urdf(str(ROOT / "examples" / "slider.urdf")).model
    sim = fd.Simulation(model, dt=1.0 / 30.0)
    if guard is not None:
        options = sim.options
        options.guard = guard
        sim.set_options(options)
    sim.set_drive("slide", fd.Drive("force", 900.0, 10.0, target_position=0.5))
    return sim


def test_options_guard_defaults_and_counters():
    assert fd.SimulationOptions().guard.enabled is False
    guard = fd.StepGuard(max_joint_step=0.06)
    assert guard.enabled and guard.max_substeps == 64
    assert repr(guard).startswith("StepGuard(enabled=True, max_joint_step=0.0")
    sim = slider_sim(guard)
    assert sim.options.guard.max_joint_step == 0.06
    substeps = []
    for _ in range(20):
        sim.step()
        substeps.append(sim.guard_substeps)
    # The first steps move the slider by more than 0.06 m: redone as 2, 4, ... sub-steps.
    assert substeps[0] > 1 and set(substeps) <= {1, 2, 4, 8, 16, 32, 64}
    assert sim.guard_triggers == sum(n > 1 for n in substeps)
    assert sim.guard_exhausted == 0
    sim.reset_guard_counters()
    assert sim.guard_triggers == 0


def test_not_triggering_is_the_unguarded_step_bit_for_bit():
    plain, guarded = slider_sim(None), slider_sim(fd.StepGuard(max_joint_step=10.0))
    for _ in range(50):
        plain.step()
        guarded.step()
        assert hexes(plain.q) == hexes(guarded.q) and hexes(plain.qd) == hexes(guarded.qd)
        assert hexes(plain.drive_force) == hexes(guarded.drive_force)
    assert guarded.guard_triggers == 0


def test_scene_guard_key(tmp_path):
    text = (f"model: {ROOT / 'examples' / 'slider.urdf'}\nsteps: 10\n"
            "guard: {max_joint_step: 0.1, max_substeps: 8}\n")
    scene = fd.parse_scene(text, str(tmp_path / "s.yaml"))
    sim = fd.make_simulation(scene)
    assert sim.options.guard.enabled and sim.options.guard.max_substeps == 8
    with pytest.raises(ValueError, match=r"guard\.max_joint_step = -1: must be finite and > 0"):
        fd.parse_scene(text.replace("0.1,", "-1,"), str(tmp_path / "s.yaml"))


@pytest.mark.parametrize("kwargs, message", [
    (dict(max_joint_step=-0.5), "guard.max_joint_step = -0.5 must be finite and > 0"),
    (dict(max_joint_step=float("nan")), "guard.max_joint_step = nan must be finite and > 0"),
    (dict(max_substeps=0), "guard.max_substeps"),
    (dict(max_substeps=10**6), "guard.max_substeps"),
    (dict(energy_tolerance=0.0), "guard.energy_tolerance = 0 must be in (0, 1]"),
    (dict(dissipation_share=0.0), "guard.dissipation_share = 0 must be in (0, 100]"),
    (dict(dissipation_share=101.0), "guard.dissipation_share = 101 must be in (0, 100]"),
])
def test_bad_bounds_raise_one_value_error(kwargs, message):
    with pytest.raises(ValueError) as error:
        fd.StepGuard(**kwargs)
    assert message in str(error.value) and "\n" not in str(error.value)
    guard = fd.StepGuard()
    with pytest.raises(ValueError):
        for key, value in kwargs.items():
            setattr(guard, key, value)
    assert (guard.max_joint_step, guard.max_substeps, guard.energy_tolerance,
            guard.dissipation_share) == (0.25, 64, 0.02, 0.15)
