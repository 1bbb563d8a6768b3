"""fd.check (docs/stability_check.md) on the slider of examples/slider.urdf (2.5 kg): the
one-joint maps' spectral radii against their matrices written out here in numpy, the fixes of an
undamped explicit PD against the threshold kp dt^2/m = 4, a scene path, bad input."""
import math

import numpy as np
import pytest

import featherdrive as fd
from conftest import ROOT

SLIDER = str(ROOT / "examples" / "slider.urdf")
M = 2.5


@pytest.fixture(scope="module")
def slider():
    """Gravity across the slide: the motion stays clear of the +-1 m limits."""
    return fd.load_urdf(SLIDER, fd.UrdfOptions(gravity=(0.0, -9.81, 0.0))).model


def radius(A):
    return max(abs(np.linalg.eigvals(np.array(A))))


def test_scene_path_with_an_implicit_drive_is_stable():
    report = fd.check(str(ROOT / "examples" / "slider.yaml"))
    assert report.stable and report.verdict == "stable"
    (j,) = report.joints
    assert j.joint == "slide" and j.law == fd.JointLaw.drive and j.axis == -1
    # The scene: force drive kp 400, kd 40, PGS, dt 1/60 -- one implicit Euler step (eq. S2).
    h, kp, kd = 1.0 / 60.0, 400.0, 40.0
    alpha = M / (M + h * kd + h * h * kp)
    c = alpha * h * kp / M
    assert j.mass == pytest.approx(M, rel=1e-12)
    assert j.stiffness_ratio == pytest.approx(kp * h * h / M, rel=1e-12)
    assert j.damping_ratio == pytest.approx(kd / (2 * math.sqrt(kp * M)), rel=1e-12)
    assert j.rho == pytest.approx(radius([[1 - h * c, h * alpha], [-c, alpha]]), rel=1e-9)
    assert report.robot.trial_bounded and report.robot.trial_steps >= 500


@pytest.mark.parametrize("a,b", [(0.5, 0.3), (3.0, 0.0), (3.5, 0.4), (6.0, 0.2), (50.0, 0.0)])
def test_explicit_pd_radius_is_the_semi_implicit_euler_map(slider, a, b):
    h = 0.01
    sim = fd.Simulation(slider, dt=h)
    sim.set_actuator("slide", fd.ExplicitActuator(kind="ideal_pd", stiffness=a * M / h**2,
                                                  damping=b * M / h))
    (j,) = fd.check(sim).joints
    # v1 = v0 + h (-kp q0 - kd v0) / m, q1 = q0 + h v1.
    A = [[1 - a, h * (1 - b)], [-a / h, 1 - b]]
    assert j.law == fd.JointLaw.explicit_pd
    assert j.rho == pytest.approx(radius(A), rel=1e-9)
    assert j.stable == (radius(A) <= 1 + 1e-9)


def test_fixes_of_an_unstable_explicit_pd(slider):
    h, a = 0.01, 30.0
    kp = a * M / h**2
    sim = fd.Simulation(slider, dt=h)
    sim.set_actuator("slide", fd.ExplicitActuator(kind="ideal_pd", stiffness=kp))
    sim.set_drive_target("slide", 0.1, 0.0)
    report = fd.check(sim)
    assert not report.stable
    assert report.verdict.startswith("unstable: slide (explicit_pd")
    (j,) = report.joints
    assert j.substeps == math.ceil(math.sqrt(a / 4))  # a / n^2 <= 4
    assert j.armature == pytest.approx(kp * h * h / 4 - M, rel=1e-3)
    assert j.damping < 0  # none: damping cannot help beyond a = 4
    assert sim.step_count == 0 and sim.q[0] == 0.0  # the check ran on copies


def test_bad_input(tmp_path):
    with pytest.raises(ValueError, match="no_such.yaml"):
        fd.check(str(tmp_path / "no_such.yaml"))
    bad = tmp_path / "bad.yaml"
    bad.write_text(f"model: {SLIDER}\ndt: -1\n")
    with pytest.raises(ValueError, match="dt"):
        fd.check(bad)
    with pytest.raises(TypeError, match="scene path"):
        fd.check(3)
    for steps in (-1, 100_001):
        with pytest.raises(ValueError, match="trial_steps = " + str(steps)):
            fd.check(str(ROOT / "examples" / "slider.yaml"), trial_steps=steps)


def test_trial_steps(slider):
    sim = fd.Simulation(slider, dt=0.01)
    assert fd.check(sim, trial_steps=0).robot.trial_steps == 0
    assert fd.check(sim, trial_steps=1234).robot.trial_steps == 1234
