"""compat='physx', link parameters and the joint friction coefficient from Python."""
import math

import pytest

import featherdrive as fd


def test_compat_physx_defaults(arm):
    plain = fd.Simulation(arm)
    physx = fd.Simulation(arm, compat="physx")
    assert physx.options.compat == fd.Compat.physx
    assert plain.options.compat == fd.Compat.none
    p = physx.link_parameters(0)
    assert (p.cfm_scale, p.linear_damping, p.angular_damping) == (0.025, 0.05, 0.05)
    assert (p.max_linear_velocity, p.max_angular_velocity) == (100.0, 50.0)
    q = plain.link_parameters(0)
    assert (q.cfm_scale, q.linear_damping, q.max_angular_velocity) == (0.0, 0.0, math.inf)
    assert physx.friction_coefficient(0) == 0.05
    assert plain.friction_coefficient(0) == 0.0
    options = fd.SimulationOptions(compat=fd.Compat.physx)
    assert fd.Simulation(arm, options).friction_coefficient(1) == 0.05


def test_set_parameters_changes_the_motion(arm):
    a, b = fd.Simulation(arm), fd.Simulation(arm)
    for s in (a, b):  # at rest the URDF's joint friction holds the arm: nothing to damp
        s.set_qd([2.0] * arm.nv)
    name = arm.links[2].name
    b.set_link_parameters(name, fd.LinkParameters(linear_damping=5.0, angular_damping=5.0))
    assert b.link_parameters(2).linear_damping == 5.0
    b.set_friction_coefficient(0, 0.3)
    assert b.friction_coefficient(0) == 0.3
    a.step(30)
    b.step(30)
    assert abs(a.q - b.q).max() > 1e-6


def test_errors_name_field_and_value(arm):
    sim = fd.Simulation(arm)
    with pytest.raises(ValueError, match=r"cfm_scale = 2 must be in \[0, 1\]"):
        sim.set_link_parameters(1, fd.LinkParameters(cfm_scale=2.0))
    with pytest.raises(ValueError, match=r"friction_coefficient = -1 must be finite and >= 0"):
        sim.set_friction_coefficient(0, -1.0)
    with pytest.raises(ValueError, match=r"compat = 'bullet': must be 'none' or 'physx'"):
        fd.Simulation(arm, compat="bullet")
