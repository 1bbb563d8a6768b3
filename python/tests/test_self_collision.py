"""Self-collision from Python (docs/math/contact.md, section 14): fd.ContactOptions(self_collision=
True) makes a robot's shapes on links that are not parent and child touch. A ball on two sliders
comes to rest on a sphere of its own fixed base: centre distance r1 + r2 and its weight carried,
both closed forms; the report names both links."""
import pathlib

import pytest

import featherdrive as fd

STACK = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "stack.urdf"


def test_a_ball_rests_on_its_own_base():
    model = fd.load_urdf(str(STACK)).model
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
