"""Collision geometry and the ground from Python (issue 34): Model.shapes from URDF and MJCF,
fd.Ground / fd.ContactOptions on a Simulation with their checks, a scene's ground, contact and
shapes keys, contacts() and link_contact_force(). Expectations come from the files themselves."""
import gzip
import math
import pathlib
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import featherdrive as fd
from conftest import in_lanes

ROOT = pathlib.Path(__file__).resolve().parents[2]
COLLISIONS = ROOT / "tests" / "data" / "collisions.urdf"
CHAIN = ROOT / "examples" / "chain3.urdf"
ANT = pathlib.Path("/usr/share/doc/dart/data/mjcf/openai/ant.xml.gz")


def test_urdf_collisions_are_shapes_on_their_links():
    robot = fd.load_urdf(str(COLLISIONS))
    shapes = robot.model.shapes
    assert [s.name for s in shapes] == ["body", "", "wheel", "lens", "arm_box", "palm"]
    assert [robot.model.links[s.link].name for s in shapes] == ["base"] * 4 + ["arm"] * 2
    assert shapes[0].type == fd.ShapeType.box
    np.testing.assert_array_equal(shapes[0].size, [0.2, 0.1, 0.05])  # half the <box size>
    assert shapes[1].type == fd.ShapeType.sphere
    assert shapes[2].type == fd.ShapeType.cylinder
    np.testing.assert_array_equal(shapes[2].size, [0.1, 0.025, 0])  # half the <cylinder length>
    np.testing.assert_allclose(shapes[3].position, [0.18, 0.01, 0.13], atol=1e-15)
    assert shapes[0].material.static_friction == 0.5
    assert robot.model.unsupported_shapes == [
        "link 'arm': mesh collision 'package://collisions/arm.ply' "
        "(meshes are read from STL, OBJ, MSH, DAE)"]
    assert robot.ground is None


def test_mesh_collisions_are_convex_hulls():
    # DART's KR5: every <collision> is an STL mesh, whose hull MuJoCo's compiler computes.
    robot = fd.load_urdf("/usr/share/doc/dart/data/urdf/KR5/KR5 sixx R650.urdf")
    shapes = robot.model.shapes
    assert len(shapes) == 7 and robot.model.unsupported_shapes == []
    for s in shapes:
        assert s.type == fd.ShapeType.convex
        assert s.vertices.shape[1] == 3 and s.vertices.shape[0] >= 4
        assert np.isfinite(s.vertices).all()
    first = shapes[0]
    assert first.vertices is not first.vertices  # a new array each time
    assert fd.load_urdf(str(COLLISIONS)).model.shapes[0].vertices.shape == (0, 3)  # a box


def test_a_collada_collision_is_a_convex_hull():
    # tests/data/collada/box.urdf: a .dae box of 25 x 25 x 50 cm once its nodes place it (units of
    # 1 cm, <translate>, <rotate>, <scale>); the corners' heights are the file's, +-25 cm about 3 cm.
    robot = fd.load_urdf(str(ROOT / "tests" / "data" / "collada" / "box.urdf"))
    assert robot.model.unsupported_shapes == []
    (shape,) = robot.model.shapes
    assert shape.type == fd.ShapeType.convex
    assert shape.vertices.shape == (8, 3)
    np.testing.assert_allclose(sorted(set(np.round(shape.vertices[:, 2], 12))), [-0.22, 0.28],
                               atol=1e-12)
    sim = fd.Simulation(robot.model)
    sim.set_ground(fd.Ground(height=-1.0))  # a .dae hull is no obstacle to a ground
    assert sim.ground().enabled


def test_a_ground_is_refused_beside_unsupported_geometry():
    sim = fd.Simulation(fd.load_urdf(str(COLLISIONS)).model)
    with pytest.raises(ValueError, match=r"^ground: link 'arm': mesh collision "
                                         r"'package://collisions/arm.ply' "
                                         r"\(meshes are read from STL, OBJ, MSH, DAE\): "
                                         r"contacts do not support this shape yet"):
        sim.set_ground(fd.Ground())
    assert not sim.ground().enabled
    sim.set_ground(fd.Ground(enabled=False, height=2.0))
    assert sim.ground().height == 2.0


def test_ground_and_contact_options_round_trip_and_are_checked():
    sim = fd.Simulation(fd.load_urdf(str(CHAIN)).model)
    assert not sim.ground().enabled
    sim.set_ground(fd.Ground(height=-0.1, normal=[0, 0, 2],
                             material=fd.Material(0.9, 0.8, 0.2)))
    g = sim.ground()
    assert g.enabled and g.height == -0.1
    np.testing.assert_array_equal(g.normal, [0, 0, 1])  # normalised
    assert (g.material.static_friction, g.material.dynamic_friction,
            g.material.restitution) == (0.9, 0.8, 0.2)
    with pytest.raises(ValueError, match=r"ground.normal = \[0, 0, 0\]"):
        sim.set_ground(fd.Ground(normal=[0, 0, 0]))
    with pytest.raises(ValueError, match=r"ground.restitution = 2 must be in \[0, 1\]"):
        sim.set_ground(fd.Ground(material=fd.Material(restitution=2.0)))
    assert sim.ground().height == -0.1  # unchanged by the refused ones
    sim.set_contact_options(fd.ContactOptions(contact_offset=0.05, rest_offset=0.01,
                                              bounce_threshold=1.0))
    o = sim.contact_options()
    assert (o.contact_offset, o.rest_offset, o.bounce_threshold) == (0.05, 0.01, 1.0)
    with pytest.raises(ValueError, match="need 0 <= rest_offset < contact_offset"):
        sim.set_contact_options(fd.ContactOptions(contact_offset=0.01, rest_offset=0.02))
    sim.step()
    assert isinstance(sim.contacts(), list)
    force = sim.link_contact_force()
    assert force.shape == (sim.model.num_links(), 3)
    assert np.all(np.isfinite(force))


def test_the_ants_geoms_and_floor(tmp_path):
    xml = tmp_path / "ant.xml"
    xml.write_bytes(gzip.decompress(ANT.read_bytes()))
    robot = fd.load_mjcf(str(xml), fixed_base=False)
    root = ET.parse(xml).getroot()
    geoms = [g for g in root.find("worldbody").iter("geom") if g.get("type") != "plane"]
    assert len(robot.model.shapes) == len(geoms) == 13
    by_name = {s.name: s for s in robot.model.shapes}
    for g in geoms:
        s = by_name[g.get("name")]
        assert s.type == (fd.ShapeType.capsule if g.get("type") == "capsule"
                          else fd.ShapeType.sphere)
        assert s.size[0] == float(g.get("size"))
        if g.get("fromto"):
            a = np.array([float(x) for x in g.get("fromto").split()])
            assert s.size[1] == pytest.approx(0.5 * np.linalg.norm(a[3:] - a[:3]), abs=1e-12)
        assert s.material.static_friction == 1.0  # <default><geom friction="1 0.5 0.5">
    assert robot.ground is not None and robot.ground.enabled
    assert robot.ground.height == 0.0
    np.testing.assert_allclose(robot.ground.normal, [0, 0, 1])
    # A scene of it takes the floor; `ground: false` leaves it off.
    scene_text = f"model: {xml}\nfixed_base: false\ndt: 0.01\nsteps: 1\n"
    scene = fd.parse_scene(scene_text, str(tmp_path / "s.yaml"))
    assert scene.ground.enabled
    assert fd.make_simulation(scene).ground().enabled
    off = fd.parse_scene(scene_text + "ground: false\n", str(tmp_path / "s.yaml"))
    assert not fd.make_simulation(off).ground().enabled


def test_scene_keys(tmp_path):
    text = (f"model: {CHAIN}\ndt: 0.01\nsteps: 1\n"
            "ground: {height: 0.25, static_friction: 1.0}\n"
            "contact: {contact_offset: 0.03}\n"
            "shapes:\n  - {link: link3, type: sphere, radius: 0.04, name: tip}\n")
    scene = fd.parse_scene(text, str(tmp_path / "s.yaml"))
    assert scene.ground.height == 0.25 and scene.ground.material.static_friction == 1.0
    assert scene.contact.contact_offset == 0.03
    tip = scene.model.shapes[-1]
    assert tip.name == "tip" and scene.model.links[tip.link].name == "link3"
    sim = fd.make_simulation(scene)
    assert sim.ground().height == 0.25
    assert sim.contact_options().contact_offset == 0.03
    with pytest.raises(fd.InputError, match=r"s.yaml: shapes\[0\].radius = -1: must be finite"):
        fd.parse_scene(text.replace("radius: 0.04", "radius: -1"), str(tmp_path / "s.yaml"))



def test_a_scene_convex_shape_is_the_hull_of_its_vertices(tmp_path):
    """`type: convex, vertices: [...]`: the hull of the points (a cube's corners and its centre,
    which the hull leaves out) in Model.shapes; too few points are refused naming the key."""
    corners = [[x, y, z] for x in (0.1, -0.1) for y in (0.1, -0.1) for z in (0.1, -0.1)]
    text = (f"model: {CHAIN}\ndt: 0.01\nsteps: 1\n"
            f"shapes:\n  - {{link: link3, type: convex, vertices: {corners + [[0, 0, 0]]}}}\n")
    hull = fd.parse_scene(text, str(tmp_path / "s.yaml")).model.shapes[-1]
    assert hull.type == fd.ShapeType.convex
    assert hull.vertices.shape == (8, 3)
    np.testing.assert_array_equal(np.abs(hull.vertices), 0.1)
    with pytest.raises(fd.InputError, match=r"shapes\[0\].vertices = .*: 3 vertices"):
        fd.parse_scene(text.replace(str(corners + [[0, 0, 0]]), str(corners[:3])),
                       str(tmp_path / "s.yaml"))

BALL = """<robot name="ball"><link name="ball">
  <inertial><mass value="2"/><inertia ixx="0.008" iyy="0.008" izz="0.008" ixy="0" ixz="0" iyz="0"/>
  </inertial>
  <collision><geometry><sphere radius="0.1"/></geometry></collision></link></robot>"""


def test_a_ball_lands_rests_and_rolls_on_the_ground():
    """Dropped, it comes to rest at z = r carrying its weight (linear momentum of a resting
    step); pushed while slipping, it ends rolling at 5/7 of its speed (angular momentum about the
    contact line; docs/math/contact.md, section 13)."""
    robot = fd.parse_urdf(BALL, "ball.urdf", fd.UrdfOptions(fixed_base=False))
    sim = fd.Simulation(robot.model, fd.SimulationOptions(dt=0.01, position_iterations=50))
    sim.set_ground(fd.Ground(material=fd.Material(0.5, 0.5, 0.0)))
    sim.set_base_state(position=[0.0, 0.0, 0.3])
    for _ in range(200):
        sim.step()
    assert sim.base_state()["position"][2] == pytest.approx(0.1, abs=1e-9)
    reports = sim.contacts()
    assert len(reports) == 1
    assert sim.link_contact_force()[0][2] == pytest.approx(2 * 9.81, rel=1e-9)
    sim.set_base_state(position=[0.0, 0.0, 0.1], linear_velocity=[1.0, 0.0, 0.0])
    for _ in range(300):
        sim.step()
    state = sim.base_state()
    assert state["linear_velocity"][0] == pytest.approx(5.0 / 7.0, abs=1e-9)
    assert state["angular_velocity"][1] * 0.1 == pytest.approx(5.0 / 7.0, abs=1e-9)


def test_a_batch_carries_each_environments_contacts():
    """Balls of masses m_i resting on the ground in one Batch: environment i's ground carries
    m_i g (linear momentum of a resting step), bit for bit what a ball of that mass gives
    alone without SIMD lanes, within 1e-11 in them (another operation order)."""
    def resting(mass):
        robot = fd.parse_urdf(BALL.replace('mass value="2"', f'mass value="{mass!r}"'),
                              "ball.urdf", fd.UrdfOptions(fixed_base=False))
        sim = fd.Simulation(robot.model, fd.SimulationOptions(dt=0.01, position_iterations=50))
        sim.set_ground(fd.Ground(material=fd.Material(0.5, 0.5, 0.0)))
        sim.set_base_state(position=[0.0, 0.0, 0.1])
        return sim
    masses = np.array([0.5, 2.0, 3.5])
    lanes = fd.Batch(resting(2.0), len(masses))
    lanes.set_link_mass("ball", masses, scale_inertia=False)
    assert in_lanes(lanes.step_path), lanes.step_path
    lanes.step(100)
    batch = fd.Batch(resting(2.0), len(masses))
    batch.lanes = False
    batch.set_link_mass("ball", masses, scale_inertia=False)
    batch.step(100)
    np.testing.assert_allclose(lanes.link_contact_force, batch.link_contact_force, rtol=1e-11,
                               atol=1e-11)
    f = batch.link_contact_force
    assert f.shape == (3, 1, 3)
    np.testing.assert_allclose(f[:, 0, 2], masses * 9.81, rtol=1e-9)
    np.testing.assert_allclose(f[:, 0, :2], 0.0, atol=1e-12)
    for i, m in enumerate(masses):
        reports = batch.contacts(i)
        assert len(reports) == 1 and reports[0].link == 0
        alone = resting(m)
        alone.step(100)
        assert np.array_equal(alone.link_contact_force(), f[i])
        assert alone.contacts()[0].normal_impulse == reports[0].normal_impulse
    with pytest.raises(ValueError, match=r"environment index 3 is out of range \[0, 3\)"):
        batch.contacts(3)
    batch.reset([1])  # its contacts start over; the others keep theirs
    assert batch.contacts(1) == [] and not np.any(batch.link_contact_force[1])
    assert len(batch.contacts(2)) == 1 and np.array_equal(batch.link_contact_force[2], f[2])


def test_feet_sum_their_links_and_carry_the_weight():
    """tests/data/quadruped_ground.yaml's feet (one per leg: thigh and shin): at rest the four
    feet's normal forces carry m g; each foot's force is the sum of its links'."""
    scene = fd.load_scene(ROOT / "tests" / "data" / "quadruped_ground.yaml")
    assert list(scene.feet) == ["fl", "fr", "hl", "hr"]
    assert scene.feet["hl"] == ["hl_thigh", "hl_shin"]
    sim = fd.make_simulation(scene)
    sim.step(1000)
    forces = sim.link_contact_force()
    names = sim.model.link_names
    total = 0.0
    for foot, links in scene.feet.items():
        f = sim.foot_contact_force(links)
        assert f.shape == (3,)
        assert np.array_equal(f, forces[names.index(links[0])] + forces[names.index(links[1])])
        total += f[2]
    mass = sum(link.mass for link in sim.model.links)
    assert total == pytest.approx(mass * 9.81, abs=1e-6)
    assert np.array_equal(sim.foot_contact_force("fl_shin"), forces[names.index("fl_shin")])
    assert np.array_equal(sim.foot_contact_force([names.index("fl_shin"), "fl_shin"]),
                          forces[names.index("fl_shin")])  # each link once
    with pytest.raises(ValueError, match="no link or frame named 'fl_shn'"):
        sim.foot_contact_force(["fl_shn"])


def test_a_contact_force_that_overflows_is_a_divergence():
    """dt = 1e-100 and an impact at 1e210 m/s: the impulse is finite, impulse / dt is not. The
    step throws DivergenceError naming the link and leaves the state as it was, with no contacts
    reported (found by fuzz_step)."""
    robot = fd.parse_urdf(BALL, "ball.urdf", fd.UrdfOptions(fixed_base=False))
    sim = fd.Simulation(robot.model, fd.SimulationOptions(dt=1e-100))
    sim.set_ground(fd.Ground())
    sim.set_base_state(position=[0.0, 0.0, 0.1], linear_velocity=[0.0, 0.0, -1e210])
    q, qd = np.array(sim.q), np.array(sim.qd)
    with pytest.raises(fd.DivergenceError, match=r"^simulation diverged at step 1 \(t = 0 s\): "
                       r"link 'ball' contact force fz = inf; the state is left as it was"):
        sim.step()
    assert np.array_equal(sim.q, q) and np.array_equal(sim.qd, qd) and sim.step_count == 0
    assert sim.contacts() == [] and not np.any(sim.link_contact_force())
