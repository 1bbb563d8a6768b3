"""The viewer's Python side (python/featherdrive_view.py, bind_view.cpp; docs/viewer.md): the
poses it gives the page against fd.link_pose and the URDF's fixed joints composed by hand, the
equivalent-inertia box against a box's closed-form inertia, the page's targets against the sine,
and its bad inputs. The page in a browser: tests/cli/view_arm.py, view_contacts.py (cli.view)."""
import json
import math
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

import featherdrive as fd
import featherdrive_view
from conftest import ARM, ROOT

SCENE = ROOT / "examples" / "arm7_pgs.yaml"
HAVE_BUNDLE = featherdrive_view.bundle_path().is_file()
needs_bundle = pytest.mark.skipif(not HAVE_BUNDLE, reason="no viewer bundle (node at build time)")


def rotation_of(quaternion):
    w, x, y, z = quaternion
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def rz(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def page_data(page):
    text = page.html
    start = text.index('id="fd-data">') + len('id="fd-data">')
    return json.loads(text[start:text.index("</script>", start)])


def test_link_world_poses_are_the_kinematics_and_the_fixed_joints():
    robot = fd.load_urdf(str(ARM))
    model = robot.model
    rows = np.random.default_rng(3).uniform(-1.5, 1.5, (4, model.nq))
    names, poses = fd.link_world_poses(model, rows, robot)
    assert poses.shape == (4, len(names), 7)
    assert set(robot.merged) == {"base_link", "hand", "tcp"}
    assert names == model.link_names + sorted(robot.merged)
    for t, q in enumerate(rows):
        for i, name in enumerate(model.link_names):
            rotation, position = fd.link_pose(model, q, name)
            np.testing.assert_allclose(poses[t, i, :3], position, atol=1e-14)
            np.testing.assert_allclose(rotation_of(poses[t, i, 3:]), rotation, atol=1e-14)
        # arm7.urdf: hand at xyz 0 0 0.06, rpy 0 0 pi/4 in link7; tcp at 0 0 0.1 in hand.
        r7, p7 = fd.link_pose(model, q, "link7")
        hand, tcp = names.index("hand"), names.index("tcp")
        np.testing.assert_allclose(poses[t, hand, :3], p7 + r7 @ [0, 0, 0.06], atol=1e-14)
        np.testing.assert_allclose(rotation_of(poses[t, hand, 3:]), r7 @ rz(math.pi / 4),
                                   atol=1e-14)
        np.testing.assert_allclose(poses[t, tcp, :3], p7 + r7 @ [0, 0, 0.16], atol=1e-14)
    assert robot.merged["tcp"][0] == "link7"


def test_link_world_poses_refuses_bad_rows():
    model = fd.load_urdf(str(ARM)).model
    with pytest.raises(ValueError, match=r"q has shape \(3,\), expected \(T, 7\)"):
        fd.link_world_poses(model, np.zeros(3))
    rows = np.zeros((2, model.nq))
    rows[1, 2] = np.nan
    with pytest.raises(ValueError, match="q row 1"):
        fd.link_world_poses(model, rows)
    with pytest.raises(TypeError, match="robot must be a UrdfRobot or None, not str"):
        fd.link_world_poses(model, rows[:1], "arm7.urdf")
    other = fd.load_urdf(str(ROOT / "examples" / "pendulum.urdf"))
    with pytest.raises(ValueError, match="pendulum.urdf: its links are not the model's"):
        fd.link_world_poses(model, rows[:1], other)


def test_inertia_box_is_the_box_of_that_inertia():
    # A 0.08 x 0.16 x 0.06 box of 0.8 kg, its sides turned by 30 degrees about z.
    mass, sides = 0.8, np.array([0.08, 0.16, 0.06])
    diagonal = mass / 12 * np.array([sides[1] ** 2 + sides[2] ** 2, sides[0] ** 2 + sides[2] ** 2,
                                     sides[0] ** 2 + sides[1] ** 2])
    turn = rz(math.radians(30))
    inertia = turn @ np.diag(diagonal) @ turn.T
    link = fd.make_link("box", "", mass, [0.1, 0.2, 0.3], inertia, fd.fixed_joint("weld"))
    model = fd.ModelBuilder().add_link(link).build()
    box = featherdrive_view._inertia_boxes(model)["box"]
    axes = np.array(box["axes"]).reshape(3, 3).T  # columns: the box's axes
    np.testing.assert_allclose(box["center"], [0.1, 0.2, 0.3])
    np.testing.assert_allclose(axes @ np.diag(box["size"]) ** 2 @ axes.T,
                               turn @ np.diag(sides) ** 2 @ turn.T, atol=1e-12)
    assert np.linalg.det(axes) == pytest.approx(1.0)


@needs_bundle
def test_page_of_a_scene(tmp_path):
    page = fd.view(str(SCENE), tmp_path / "arm.html", steps=12)
    assert page.path == tmp_path / "arm.html" and page.path.read_text() == page.html
    assert page.frames == 13 and page.warnings == []
    data = page_data(page)
    assert [j["name"] for j in data["joints"]] == [f"joint{k}" for k in range(1, 8)]
    dt = 1 / 60
    # joint1's target: 0.8 sin(2 pi 0.25 t), t = dt for the initial row (the first step's target)
    # and k dt for row k.
    joint1 = data["joints"][0]
    expected = [0.8 * math.sin(2 * math.pi * 0.25 * max(k, 1) * dt) for k in range(13)]
    np.testing.assert_allclose(joint1["target"], expected, atol=1e-9)
    assert joint1["max_force"] == 150 and joint1["force"][0] == 0
    assert data["urdf"] == ARM.read_text() and data["marker"] is None
    assert len(data["poses"]) == 13 * len(data["links"]) * 7
    assert "<iframe srcdoc=\"&lt;!DOCTYPE html&gt;" in page._repr_html_()


@needs_bundle
def test_contact_arrows_of_a_simulation(tmp_path):
    """A 2 kg ball resting on the ground: one arrow per stepped frame, from its contact point
    (0, 0, 0) along its force, (0, 0, m g); 1 m per the robot's weight m g (docs/viewer.md, (2));
    none in the first frame and none without a ground."""
    robot = fd.parse_urdf('<robot name="ball"><link name="ball"><inertial><mass value="2"/>'
                          '<inertia ixx="0.008" iyy="0.008" izz="0.008" ixy="0" ixz="0" iyz="0"/>'
                          '</inertial><collision><geometry><sphere radius="0.1"/></geometry>'
                          '</collision></link></robot>', "ball.urdf",
                          fd.UrdfOptions(fixed_base=False))
    sim = fd.Simulation(robot.model, fd.SimulationOptions(dt=0.01, position_iterations=50))
    sim.set_ground(fd.Ground())
    sim.set_base_state(position=[0.0, 0.0, 0.1])
    contacts = page_data(fd.view(sim, tmp_path / "ball.html", steps=3))["contacts"]
    assert contacts["per_newton"] == pytest.approx(1 / (2 * 9.81), rel=1e-15)
    frames = contacts["frames"]
    assert len(frames) == 4 and frames[0] == []
    for arrow in frames[1:]:
        np.testing.assert_allclose(arrow, [0, 0, 0, 0, 0, 0, 2 * 9.81], atol=1e-6)
    sim.set_ground(fd.Ground(enabled=False))
    assert page_data(fd.view(sim, tmp_path / "air.html", steps=1))["contacts"] is None


@needs_bundle
def test_mjcf_robots_carry_their_inertia_boxes(tmp_path):
    scene = ROOT / "examples" / "humanoid_hold.yaml"
    model = fd.load_scene(str(scene)).model
    data = page_data(fd.view(str(scene), tmp_path / "h.html", steps=1))
    assert data["urdf"] is None and data["meshes"] == {}
    assert sorted(data["boxes"]) == sorted(link.name for link in model.links if link.mass > 0)


@needs_bundle
def test_page_carries_the_collision_shapes_and_the_ground(tmp_path):
    # The Ant (examples/ant.xml): a torso sphere of radius 0.25 and 12 capsules of radius 0.08,
    # 8 from fromto vectors of length 0.2 sqrt(2) (half 0.1 sqrt(2)) and 4 (the ankles) of
    # 0.4 sqrt(2); the floor is the scene's ground z = 0.
    data = page_data(fd.view(str(ROOT / "examples" / "ant_walk.yaml"), tmp_path / "a.html",
                             steps=1))
    shapes = [s for link in data["shapes"].values() for s in link]
    spheres = [s["size"][0] for s in shapes if s["type"] == "sphere"]
    capsules = sorted(round(s["size"][1] / math.sqrt(2), 9) for s in shapes
                      if s["type"] == "capsule")
    assert spheres == [pytest.approx(0.25)] and len(shapes) == 13
    assert capsules == [0.1] * 8 + [0.2] * 4
    assert all(s["size"][0] == pytest.approx(0.08) for s in shapes if s["type"] == "capsule")
    for s in shapes:  # the shape's axes are a rotation
        axes = np.reshape(s["axes"], (3, 3))
        np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-12)
    assert data["ground"] == {"normal": [0.0, 0.0, 1.0], "height": 0.0}
    arm = page_data(fd.view(str(SCENE), tmp_path / "arm.html", steps=1))
    assert arm["ground"] is None


@needs_bundle
def test_page_of_a_csv_needs_the_csv_columns(tmp_path):
    good = tmp_path / "run.csv"
    good.write_text("step,t," + ",".join(f"q:joint{k}" for k in range(1, 8)) + "\n"
                    + "0,0," + ",".join(["0.1"] * 7) + "\n" + "1,0.1," + ",".join(["0.2"] * 7)
                    + "\n")
    page = fd.view(str(good), tmp_path / "run.html", scene=str(SCENE))
    assert page_data(page)["joints"][2]["q"] == [0.1, 0.2]
    bad = tmp_path / "bad.csv"
    bad.write_text("step,t,q:joint1\n0,0,0\n")
    with pytest.raises(ValueError, match=r"bad.csv: no column 'q:joint2'"):
        fd.view(str(bad), tmp_path / "bad.html", scene=str(SCENE))
    bad.write_text(good.read_text().replace("0.2,", "x,", 1))
    with pytest.raises(ValueError, match=r"bad.csv: row 2, column q:joint1: 'x' is not a number"):
        fd.view(str(bad), tmp_path / "bad.html", scene=str(SCENE))
    with pytest.raises(ValueError, match="steps = 3 is for a run of the scene"):
        fd.view(str(good), tmp_path / "bad.html", scene=str(SCENE), steps=3)
    with pytest.raises(ValueError, match="a CSV needs the scene"):
        fd.view(str(good), tmp_path / "bad.html")
    assert not (tmp_path / "bad.html").exists()


@needs_bundle
def test_csv_of_a_floating_robot_gives_the_run_s_poses(tmp_path, module_dir):
    # The arm with a floating root, 5 steps: the page of `featherdrive simulate`'s CSV (its
    # q:root_joint:x ... qz columns read back) poses every link as the page of the run itself.
    scene = tmp_path / "floating.yaml"
    scene.write_text(SCENE.read_text().replace("model: arm7.urdf", f"model: {ARM}")
                     .replace("fixed_base: true", "fixed_base: false"))
    run_csv = tmp_path / "run.csv"
    cli = module_dir.parent / "tools" / "featherdrive"
    subprocess.run([str(cli), "simulate", str(scene), "--steps", "5", "--out", str(run_csv)],
                   check=True, capture_output=True)
    assert "q:root_joint:qz" in run_csv.read_text().splitlines()[0]
    of_run = page_data(fd.view(str(scene), tmp_path / "a.html", steps=5))
    of_csv = page_data(fd.view(str(run_csv), tmp_path / "b.html", scene=str(scene)))
    assert of_csv["links"] == of_run["links"] and len(of_run["times"]) == 6
    assert of_csv["poses"] == of_run["poses"]
    assert of_csv["joints"] == of_run["joints"]
    # The root moved (it falls): the poses are not those of the initial state repeated.
    assert of_run["poses"][2] != of_run["poses"][-len(of_run["links"]) * 7 + 2]


@needs_bundle
def test_bad_inputs_leave_files_alone(tmp_path):
    scene = tmp_path / "arm.yaml"
    scene.write_text(SCENE.read_text().replace("model: arm7.urdf", f"model: {ARM}"))
    before = scene.read_text()
    with pytest.raises(ValueError, match=r"--out .*arm.yaml: is the scene"):
        fd.view(str(scene), scene.with_suffix(".yaml"), steps=1)
    assert scene.read_text() == before
    with pytest.raises(ValueError, match="is not a regular file"):
        fd.view(str(scene), tmp_path, steps=1)
    with pytest.raises(ValueError, match="marker: no link 'hnd'"):
        fd.view(str(scene), tmp_path / "a.html", steps=1, marker="hnd")
    with pytest.raises(ValueError, match="steps = -1"):
        fd.view(str(scene), tmp_path / "a.html", steps=-1)
    with pytest.raises(TypeError, match="not int"):
        fd.view(3, tmp_path / "a.html")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arm.yaml"]


@needs_bundle
def test_meshes_inlined_or_reported(tmp_path):
    mesh = tmp_path / "m.stl"
    mesh.write_bytes(b"solid m\nendsolid m\n")
    urdf = ARM.read_text().replace(
        '<link name="link7">',
        '<link name="link7"><visual><geometry><mesh filename="package://kit/m.stl"/>'
        '</geometry></visual><visual><geometry><mesh filename="package://gone/x.stl"/>'
        '</geometry></visual>')
    (tmp_path / "arm.urdf").write_text(urdf)
    robot = fd.load_urdf(str(tmp_path / "arm.urdf"))
    with pytest.warns(UserWarning, match=r"link 'link7' mesh package://gone/x.stl: package "
                                         r"'gone' is not mapped \(--package gone=DIR\)"):
        page = fd.view(fd.Simulation(robot.model), tmp_path / "p.html", robot=robot,
                       packages={"kit": str(tmp_path)})
    assert list(page_data(page)["meshes"]) == ["package://kit/m.stl"]


def test_missing_bundle_is_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("FEATHERDRIVE_VIEWER_BUNDLE", str(tmp_path / "none.js"))
    node = shutil.which("node") and shutil.which("npm")
    assert featherdrive_view.main([str(SCENE), "--out", str(tmp_path / "a.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("featherdrive view: ")
    assert ("featherdrive_viewer" if node else "apt-get install -y nodejs npm") in err
    assert not (tmp_path / "a.html").exists()


def test_command_line_errors_exit_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        featherdrive_view.main([str(SCENE), "--package", "nofolder"])
    assert exit_.value.code == 2
    assert "'nofolder' is not NAME=DIR" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:
        featherdrive_view.main([str(SCENE), "--port", "8001"])
    assert exit_.value.code == 2
    assert capsys.readouterr().err == ("featherdrive view: --port 8001: only with --serve (see "
                                       "featherdrive view --help)\n")
    if HAVE_BUNDLE:
        missing = tmp_path / "missing.yaml"
        assert featherdrive_view.main([str(missing), "--out", str(tmp_path / "a.html")]) == 2
        err = capsys.readouterr().err
        assert err == f"featherdrive view: {missing}: cannot open the scene: " \
                      "No such file or directory\n"


# Hardening (issue 36): inputs as the C++ commands read them, arguments, outputs.

def good_csv(path):
    path.write_text("step,t," + ",".join(f"q:joint{k}" for k in range(1, 8)) + "\n"
                    + "0,0," + ",".join(["0.1"] * 7) + "\n" + "1,0.1," + ",".join(["0.2"] * 7)
                    + "\n")
    return path


@needs_bundle
def test_csv_inputs_are_regular_decimal_utf8(tmp_path):
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    for source, why in (("/dev/zero.csv", "cannot open the CSV"),
                        (str(fifo), "is not a regular file (a FIFO)")):
        with pytest.raises(ValueError, match="^" + re.escape(f"{source}: {why}")):
            fd.view(source, tmp_path / "a.html", scene=str(SCENE))
    good = good_csv(tmp_path / "run.csv")
    data = good.read_bytes()
    offset = data.index(b"0.2")
    (tmp_path / "latin.csv").write_bytes(data[:offset] + b"\xff" + data[offset + 1:])
    with pytest.raises(ValueError, match=rf"latin\.csv: line 3, byte offset {offset}: byte 0xff "
                                         "is not UTF-8"):
        fd.view(str(tmp_path / "latin.csv"), tmp_path / "a.html", scene=str(SCENE))
    (tmp_path / "under.csv").write_text(good.read_text().replace("0.2,", "0_2,", 1))
    with pytest.raises(ValueError, match=r"under\.csv: row 2, column q:joint1: '0_2' is not a "
                                         "number"):
        fd.view(str(tmp_path / "under.csv"), tmp_path / "a.html", scene=str(SCENE))
    (tmp_path / "bom.csv").write_bytes(b"\xef\xbb\xbf" + data)
    assert page_data(fd.view(str(tmp_path / "bom.csv"), tmp_path / "b.html",
                             scene=str(SCENE)))["joints"][2]["q"] == [0.1, 0.2]
    assert not (tmp_path / "a.html").exists()


@needs_bundle
@pytest.mark.parametrize("kw,error,match", [
    ({"title": 3}, TypeError, r"title = 3: must be a str or None, not int"),
    ({"marker": 3}, TypeError, r"marker = 3: must be a str or None, not int"),
    ({"out": 3}, TypeError, r"out = 3: must be a path"),
    ({"steps": 10**9}, ValueError, r"steps = 1000000000: must be in \[0, 1000000\]"),
    ({"packages": ["kit"]}, TypeError, r"packages must be a dict"),
    ({"scene": 3}, TypeError, r"scene must be a scene path or a Scene, not int"),
])
def test_bad_arguments_name_the_argument(tmp_path, kw, error, match):
    args = dict(out=tmp_path / "a.html") | kw
    with pytest.raises(error, match=match):
        fd.view(str(SCENE), **args)
    assert not (tmp_path / "a.html").exists()


@needs_bundle
def test_the_page_never_replaces_the_csv_or_the_model(tmp_path):
    scene = tmp_path / "arm.yaml"
    scene.write_text(SCENE.read_text().replace("model: arm7.urdf", f"model: {ARM}"))
    run = good_csv(tmp_path / "run.csv")
    (tmp_path / "run.html").symlink_to(run)
    with pytest.raises(ValueError, match=r"--out .*run\.html: is the CSV"):
        fd.view(str(run), tmp_path / "run.html", scene=str(scene))
    (tmp_path / "model.html").symlink_to(ARM)
    with pytest.raises(ValueError, match=r"--out .*model\.html: is the scene's model"):
        fd.view(str(scene), tmp_path / "model.html", steps=1)
    old = os.umask(0o027)
    try:
        page = fd.view(str(scene), tmp_path / "p.html", steps=1)
    finally:
        os.umask(old)
    assert oct(page.path.stat().st_mode & 0o777) == oct(0o640)


@needs_bundle
def test_the_command_refuses_non_regular_inputs(tmp_path, module_dir):
    command = str(module_dir.parent / "tools" / "featherdrive")
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    for args, message in [(["/dev/zero"], "/dev/zero: is not a regular file (a character device)"),
                          ([str(SCENE), "--csv", str(fifo)], f"{fifo}: is not a regular file "
                                                             "(a FIFO)")]:
        r = subprocess.run([command, "view", *args, "--out", str(tmp_path / "a.html")],
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert message in r.stderr
    assert not (tmp_path / "a.html").exists()
