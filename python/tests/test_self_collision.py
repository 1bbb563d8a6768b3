"""Self-collision from Python (docs/math/contact.md, section 14): fd.ContactOptions(self_collision=
True) makes a robot's shapes on links that are not parent and child touch. A ball on two sliders
comes to rest on a sphere of its own fixed base: centre distance r1 + r2 and its weight carried,
both closed forms; the report names both links."""
import pytest

import featherdrive as fd

STACK = """<robot name="stack">
  <link name="base"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
  <joint name="across" type="prismatic"><parent link="base"/><child link="carriage"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="100" velocity="10"/></joint>
  <link name="carriage"><inertial><mass value="0.5"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="drop" type="prismatic"><parent link="carriage"/><child link="ball"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="100" velocity="10"/></joint>
  <link name="ball"><inertial><mass value="2"/>
    <inertia ixx="0.002" iyy="0.002" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><sphere radius="0.05"/></geometry></collision></link>
</robot>"""


def test_a_ball_rests_on_its_own_base():
    model = fd.parse_urdf(STACK, "stack.urdf").model
    sim = fd.Simulation(model, fd.SimulationOptions(dt=0.01, position_iterations=50))
    assert not sim.contact_options().self_collision
    sim.set_contact_options(fd.ContactOptions(self_collision=True))
    assert "self_collision=True" in repr(sim.contact_options())
    sim.set_q([0.0, 0.16])
    for _ in range(300):
        sim.step()
    assert sim.q[1] == pytest.approx(0.15, abs=1e-9)
    (report,) = sim.contacts()
    links = [l.name for l in model.links]
    assert (links[report.link], links[report.other_link]) == ("base", "ball")
    assert report.other_shape == 1
    assert report.normal_impulse / 0.01 == pytest.approx(2 * 9.81, rel=1e-9)
    assert sim.link_contact_force()[links.index("ball")][2] == pytest.approx(2 * 9.81, rel=1e-7)
