"""The MuJoCo bridge from Python (docs/mujoco_bridge.md): the per-step map against a step of the
Simulation, the translation's closed form (eq. B7), the MJCF export and bad input. MuJoCo itself
runs the translations in tests/peers/mujoco_bridge_test.cpp."""
import numpy as np
import pytest

import featherdrive as fd
from conftest import ROOT

SLIDER = str(ROOT / "examples" / "slider.urdf")
M, DT = 2.5, 1.0 / 60.0


@pytest.fixture(scope="module")
def slider():
    """Gravity across the slide: the map's force input is 0."""
    return fd.load_urdf(SLIDER, fd.UrdfOptions(gravity=(0.0, -9.81, 0.0))).model


@pytest.mark.parametrize("solver", ["pgs", "tgs"])
def test_step_map_is_one_step_of_the_simulation(slider, solver):
    options = fd.SimulationOptions(dt=DT, solver=solver, position_iterations=4)
    drive = fd.Drive("force", stiffness=900.0, damping=30.0, target_position=0.2,
                     target_velocity=0.5)
    m = fd.effective_inertia(slider, np.zeros(1))[0]
    assert m == pytest.approx(M, rel=1e-12)
    step = fd.physx_step_map(m, drive, options)
    sim = fd.Simulation(slider, options)
    sim.set_drive("slide", drive)
    sim.set_q(np.array([0.05]))
    sim.set_qd(np.array([-0.3]))
    sim.step()
    expected = step.A @ np.array([0.05, -0.3]) + step.B @ np.array([0.2, 0.5, 0.0])
    np.testing.assert_allclose([sim.q[0], sim.qd[0]], expected, rtol=0, atol=1e-14)


def test_translation_carries_the_implicit_stiffness_in_the_damping():
    options = fd.SimulationOptions(dt=DT, solver="tgs", position_iterations=4)
    t = fd.translate_to_mujoco(M, fd.Drive("force", stiffness=900.0, damping=30.0), options)
    assert t.exact and t.reproducible
    assert t.mujoco.kp == 900.0 and t.mujoco.substeps == 4
    assert t.mujoco.damping == pytest.approx(30.0 + DT / 4 * 900.0, rel=1e-15)
    kept = fd.translate_to_mujoco(M, fd.Drive("force", stiffness=900.0, damping=30.0), options,
                                  keep_timestep=True)
    assert not kept.reproducible and "not reproducible" in kept.note
    back = fd.translate_to_physx(M, _pgs_mujoco(), fd.SimulationOptions(dt=DT))
    assert back.exact and back.drive.stiffness == pytest.approx(900.0, rel=1e-12)


def _pgs_mujoco():
    d = fd.MujocoDrive()
    d.kp, d.damping = 900.0, 30.0 + DT * 900.0
    return d


def test_export_mjcf(slider):
    sim = fd.Simulation(slider, fd.SimulationOptions(dt=DT))
    sim.set_drive("slide", fd.Drive("force", stiffness=400.0, damping=40.0))
    e = fd.export_mjcf(sim)
    assert e["xml"].startswith("<mujoco") and 'name="slide:position"' in e["xml"]
    assert e["substeps"] == 1 and e["timestep"] == DT
    assert e["drives"][0]["joint"] == "slide" and e["drives"][0]["translation"].exact
    literal = fd.export_mjcf(sim, drives="literal", integrator="implicit")
    assert 'name="slide:velocity"' in literal["xml"] and 'integrator="implicit"' in literal["xml"]
    assert "Euler" in fd.model_to_mjcf(slider, DT)


def test_bad_input(slider):
    options = fd.SimulationOptions()
    with pytest.raises(ValueError, match="effective inertia"):
        fd.physx_step_map(0.0, fd.Drive("force", stiffness=1.0), options)
    with pytest.raises(ValueError, match="type none"):
        fd.translate_to_mujoco(1.0, fd.Drive("none"), options)
    with pytest.raises(ValueError, match="integrator"):
        fd.translate_to_mujoco(1.0, fd.Drive("force", stiffness=1.0), options, integrator="rk4")
    with pytest.raises(ValueError, match="q has shape"):
        fd.effective_inertia(slider, np.zeros(3))
    sim = fd.Simulation(slider, options)
    with pytest.raises(ValueError, match="drives"):
        fd.export_mjcf(sim, drives="copied")


def test_numbers_out_of_range_are_refused_naming_the_argument(slider):
    """NaN, inf, negative, zero and overflowing numbers: ValueError naming the argument and the
    value, never a NaN result, an identity map or timestep="nan"."""
    options = fd.SimulationOptions()
    nan = float("nan")
    mj = fd.MujocoDrive()
    mj.kp = nan
    with pytest.raises(ValueError, match="kp = nan"):
        fd.translate_to_physx(1.0, mj, options)
    mj.kp = 100.0
    mj.substeps = -5
    with pytest.raises(ValueError, match="substeps = -5"):
        fd.mujoco_step_map(1.0, mj, DT)
    mj.substeps = 1
    for dt in (0.0, -1.0, nan, float("inf")):
        with pytest.raises(ValueError, match="dt = "):
            fd.mujoco_step_map(1.0, mj, dt)
    for field in ("kv", "damping", "armature"):
        bad = fd.MujocoDrive()
        setattr(bad, field, -1.0)
        with pytest.raises(ValueError, match=f"{field} = -1"):
            fd.mujoco_step_map(1.0, bad, DT)
    with pytest.raises(ValueError, match=r"q\[0\] = nan"):
        fd.effective_inertia(slider, np.array([nan]))
    with pytest.raises(ValueError, match="dt = nan"):
        fd.model_to_mjcf(slider, nan)
    with pytest.raises(ValueError, match="dt = 0"):
        fd.model_to_mjcf(slider, 0.0)
    with pytest.raises(ValueError, match="stiffness = nan"):
        fd.translate_to_mujoco(1.0, fd.Drive("force", stiffness=nan), options)
    with pytest.raises(ValueError, match="effective inertia m = inf"):
        fd.physx_step_map(float("inf"), fd.Drive("force", stiffness=1.0), options)
    # A drive whose translation overflows a double (damping kd + dt kp = 2e308): refused, not
    # a damping of inf.
    with pytest.raises(ValueError, match="the translated damping = inf"):
        fd.translate_to_mujoco(1.0, fd.Drive("force", stiffness=1e308, damping=1e308),
                               fd.SimulationOptions(dt=1.0))


def test_mjcf_gear_that_overflows_is_refused(tmp_path):
    """A gear of 1e200 gives gain gear^2 = inf: refused naming the file, actuator and gear."""
    xml = tmp_path / "gear.xml"
    xml.write_text(
        '<mujoco><worldbody><body name="b"><joint name="h" type="hinge"/>'
        '<geom type="sphere" size="0.1" mass="1"/></body></worldbody>'
        '<actuator><position name="act" joint="h" kp="10" gear="1e200"/></actuator></mujoco>')
    with pytest.raises(ValueError, match=r"gear.xml: actuator 'act' .*\(gear 1e\+200\) = inf"):
        fd.translate_mjcf_to_scene(str(xml), str(tmp_path / "s.yaml"))


def test_mjcf_drives_to_a_scene(tmp_path):
    """A MuJoCo position actuator with joint damping 40 >= dt kp = 15: PGS's drive is kp and
    40 - dt kp (eq. B11), and the scene text loads."""
    xml = tmp_path / "slider.xml"
    xml.write_text('<mujoco><option timestep="0.016666666666666666"/><worldbody>'
                   '<body name="cart"><joint name="slide" type="slide" axis="1 0 0" damping="40"/>'
                   '<inertial pos="0 0 0" mass="2" diaginertia="0.01 0.01 0.01"/></body>'
                   '</worldbody><actuator><position joint="slide" kp="900"/></actuator></mujoco>')
    t = fd.translate_mjcf_to_scene(xml, tmp_path / "scene.yaml")
    (joint,) = t["joints"]
    assert joint["physx"].exact
    assert joint["physx"].drive.stiffness == pytest.approx(900.0, rel=1e-12)
    assert joint["physx"].drive.damping == pytest.approx(40.0 - 900.0 / 60.0, rel=1e-12)
    scene = fd.parse_scene(t["yaml"], tmp_path / "scene.yaml")
    assert scene.steps == 240
    with pytest.raises(ValueError, match="no position or velocity actuator"):
        bare = tmp_path / "bare.xml"
        bare.write_text('<mujoco><worldbody><body><joint type="slide"/>'
                        '<geom size="0.1"/></body></worldbody></mujoco>')
        fd.translate_mjcf_to_scene(bare, tmp_path / "scene.yaml")
