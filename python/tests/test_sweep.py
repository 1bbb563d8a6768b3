"""featherdrive_sweep (fd.sweep, `featherdrive sweep`): a grid point against a lone Simulation
and against `featherdrive simulate`; a damping sweep against the closed form of a second-order
system's squared error; bad grids. The cluster cases are in test_distributed.py."""
import csv
import math
import os
import re
import subprocess

import numpy as np
import pytest

import featherdrive as fd
import featherdrive_sweep
from conftest import ROOT

SLIDER = ROOT / "examples" / "slider.yaml"


def cli(module_dir):
    return str(module_dir.parent / "tools" / "featherdrive")


def lone_run(scene_path, gains, joint=None):
    """Per drive, the RMS of target - q of a lone Simulation with `gains` on the drives (or on
    `joint`'s): the same quantity by other code."""
    scene = fd.load_scene(str(scene_path))
    sim = fd.make_simulation(scene)
    drives = [d for d in scene.drives if d.drive.type != fd.DriveType.none]
    for d in drives:
        if joint is None or d.joint == joint:
            drive = sim.drive(d.dof)
            for name, value in gains.items():
                setattr(drive, name, value)
            sim.set_drive(d.dof, drive)
    model = scene.model
    errors = []
    for k in range(scene.steps):
        fd.apply_targets(scene, sim, k)
        sim.step()
        t = (k + 1) * scene.options.dt
        errors.append([d.target_at(t)[0] - sim.q[model.links[model.dof_link[d.dof]].q_index]
                       for d in drives])
    return np.sqrt(np.mean(np.square(errors), axis=0))


def test_a_grid_point_is_a_lone_simulation_run():
    result = fd.sweep(str(SLIDER), "stiffness=100:400:2,damping=5:40:3:log")
    assert result.names == ["stiffness", "damping"] and result.joints == ["slide"]
    assert result.points.shape == (6, 2)
    np.testing.assert_allclose(result.axes[1], [5.0, math.sqrt(5 * 40), 40.0], rtol=1e-15)
    for i in (0, 4):
        stiffness, damping = result.points[i]
        expected = lone_run(SLIDER, {"stiffness": stiffness, "damping": damping})
        np.testing.assert_allclose(result.rms[i], expected, rtol=1e-12)
        assert result.total[i] == pytest.approx(expected[0], rel=1e-15)  # one drive
    assert not result.diverged.any()


def test_a_row_kind_s_field_is_swept_on_the_drives_joints():
    # A spring beside the slider's drive: each point's run is a lone Simulation with the spring.
    result = fd.sweep(str(SLIDER), "joint_spring.stiffness=0:300:3,joint_spring.reference=-0.1")
    assert result.names == ["joint_spring.stiffness", "joint_spring.reference"]
    assert result.gain_units["joint_spring.stiffness"] == "N/m"
    scene = fd.load_scene(str(SLIDER))
    for i in range(3):
        k, reference = result.points[i]
        sim = fd.make_simulation(scene)
        for d in scene.drives:
            sim.set_row_parameters("joint_spring", d.dof, stiffness=k, reference=reference)
        errors = []
        for step in range(scene.steps):
            fd.apply_targets(scene, sim, step)
            sim.step()
            t = (step + 1) * scene.options.dt
            errors.append(scene.drives[0].target_at(t)[0] - sim.q[0])
        assert result.rms[i][0] == pytest.approx(math.sqrt(np.mean(np.square(errors))),
                                                 rel=1e-12)
    assert result.rms[0][0] != result.rms[2][0]  # the spring acts
    with pytest.raises(ValueError, match="joint spring of joint 'slide': stiffness = -1"):
        fd.sweep(str(SLIDER), {"joint_spring.stiffness": [-1.0]})


def test_joint_changes_one_drive_and_total_is_the_rms_of_the_drives():
    arm = ROOT / "examples" / "arm7_tgs.yaml"
    result = fd.sweep(str(arm), {"damping": [10.0, 60.0]}, joint="joint7")
    assert len(result.joints) == 7
    expected = lone_run(arm, {"damping": 60.0}, joint="joint7")
    np.testing.assert_allclose(result.rms[1], expected, rtol=1e-12)
    assert result.total[1] == pytest.approx(math.sqrt(np.mean(expected ** 2)), rel=1e-12)
    np.testing.assert_array_equal(result.objective, result.rms[:, 6])


def test_damping_sweep_follows_the_closed_form(tmp_path):
    # A 2.5 kg slider without gravity, at rest at 0, target A from the first step. For
    # m x'' + c x' + k x = k A the squared error integrates to A^2 (1 + 4 z^2) / (4 z w),
    # w = sqrt(k / m), z = c / (2 sqrt(k m)): least at z = 1/2.
    k, m, A, dt, T = 100.0, 2.5, 0.1, 1e-3, 5.0
    w, critical = math.sqrt(k / m), 2.0 * math.sqrt(k * m)
    scene = tmp_path / "step.yaml"
    scene.write_text(
        f"model: {ROOT / 'examples' / 'slider.urdf'}\nfixed_base: true\ngravity: [0, 0, 0]\n"
        f"dt: {dt}\nsteps: {round(T / dt)}\nsolver: {{type: pgs}}\n"
        f"drives:\n  slide: {{type: force, stiffness: {k}, target_position: {A}}}\n")
    zetas = np.linspace(0.2, 1.2, 21)
    result = fd.sweep(str(scene), {"damping": zetas * critical})
    closed = np.sqrt(A * A * (1 + 4 * zetas ** 2) / (4 * zetas * w) / T)
    np.testing.assert_allclose(result.total, closed, rtol=0.015)  # measured: 0.73 %
    assert zetas[result.best()] == pytest.approx(0.5)


def test_cli_writes_the_grid_and_its_plot_and_agrees_with_simulate(tmp_path, module_dir):
    out = tmp_path / "out"
    r = subprocess.run([cli(module_dir), "sweep", str(SLIDER), "--grid",
                        "stiffness=100:400:2,damping=10:40:2", "--out", str(out)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "4 grid points, 1 drives" in r.stdout and "least total rms error" in r.stdout
    with open(out / "sweep.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["stiffness", "damping", "rms:slide", "rms_total", "diverged",
                             "overshoot:slide", "settling_time:slide", "max_force:slide"]
    assert [(float(r["stiffness"]), float(r["damping"])) for r in rows] == [
        (100.0, 10.0), (100.0, 40.0), (400.0, 10.0), (400.0, 40.0)]
    assert (out / "sweep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # featherdrive simulate on the scene with the point's gains written in: its rms column.
    text = SLIDER.read_text().replace("stiffness: 400, damping: 40", "stiffness: 100, damping: 40")
    text = text.replace("model: slider.urdf", f"model: {ROOT / 'examples' / 'slider.urdf'}")
    scene = tmp_path / "point.yaml"
    scene.write_text(text)
    r = subprocess.run([cli(module_dir), "simulate", str(scene)], capture_output=True, text=True,
                       timeout=120)
    line = next(l for l in r.stdout.splitlines() if l.strip().startswith("slide"))
    rms = float(line.split()[3])
    assert float(rows[1]["rms:slide"]) == pytest.approx(rms, rel=6e-4)


BAD_GRIDS = [
    ("stiffness=10:1000", "--grid stiffness=10:1000: expected VALUE, LO:HI:N or LO:HI:N:log"),
    ("stiffness=10:1000:x", "N = 'x' must be a whole number of points"),
    ("stiffness=0:10:3:log", "log spacing needs LO > 0, not 0"),
    ("stiffness=10:1:3", "HI = 1 is below LO = 10"),
    ("stiffness=10:20:3:cubic", "spacing 'cubic' must be lin or log"),
    ("mass=1:2:3", "--grid mass: unknown parameter (expected one of stiffness, damping, "
                   "joint_spring.stiffness, joint_spring.damping, joint_spring.reference)"),
    ("stiffness=1,stiffness=2", "--grid stiffness: given twice"),
    ("stiffness", "--grid entry 'stiffness': expected NAME=LO:HI:N[:log]"),
    ("damping=-1", "must be finite and >= 0"),
]


@pytest.mark.parametrize("grid, message", BAD_GRIDS)
def test_bad_grids_are_value_errors_naming_the_entry(grid, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        featherdrive_sweep.parse_grid(grid)


def test_bad_grids_on_the_command_line_get_one_line_and_exit_2(module_dir, tmp_path):
    for grid, message in BAD_GRIDS[:3]:  # each a python start: a few suffice
        r = subprocess.run([cli(module_dir), "sweep", str(SLIDER), "--grid", grid, "--out",
                            str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert r.stderr.startswith("featherdrive sweep: ") and message in r.stderr
        assert not (tmp_path / "o").exists()


def test_bad_options_get_one_line_and_exit_2(module_dir, tmp_path):
    for args, message in [
        ([str(SLIDER)], "the following arguments are required: --grid"),
        ([str(SLIDER), "--grid", "damping=1", "--joint", "elbow"],
         "--joint elbow: not an implicit drive of"),
        ([str(tmp_path / "none.yaml"), "--grid", "damping=1"], "none.yaml"),
    ]:
        r = subprocess.run([cli(module_dir), "sweep", *args], capture_output=True, text=True,
                           timeout=120, cwd=tmp_path)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert message in r.stderr
    with pytest.raises(TypeError, match="grid must be a str or a dict"):
        fd.sweep(str(SLIDER), 3)
    # --help reaches the module through the dispatch: exit 0.
    r = subprocess.run([cli(module_dir), "sweep", "--help"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0 and "LO:HI:N:log" in r.stdout


# Hardening (issue 36): the C++ commands' file rules, the grid's size, arguments, outputs.

def slider_copy(folder):
    """The slider scene (20 steps) and its URDF in folder."""
    (folder / "slider.urdf").write_text((ROOT / "examples" / "slider.urdf").read_text())
    scene = folder / "s.yaml"
    scene.write_text(SLIDER.read_text().replace("steps: 240", "steps: 20"))
    return scene


def test_scenes_that_are_not_regular_files_are_refused_unread(tmp_path):
    fifo = tmp_path / "pipe.yaml"
    os.mkfifo(fifo)
    for scene, why in (("/dev/zero", "is not a regular file (a character device)"),
                       (str(fifo), "is not a regular file (a FIFO)"),
                       (str(tmp_path), "is a directory")):
        with pytest.raises(ValueError, match="^" + re.escape(f"{scene}: {why}")):
            fd.sweep(scene, "damping=1")


def test_the_grid_s_size_is_bounded_before_it_is_made():
    n = 31_623  # each axis within its bound, the product 1e9 points
    with pytest.raises(ValueError, match=rf"--grid: stiffness {n} x damping {n} = {n * n} points, "
                                         rf"more than {featherdrive_sweep.MAX_POINTS}"):
        featherdrive_sweep.parse_grid(f"stiffness=1:10:{n},damping=1:10:{n}")
    with pytest.raises(ValueError, match="= 1000001 points"):
        featherdrive_sweep.parse_grid({"stiffness": np.ones(1_000_001)})
    assert len(featherdrive_sweep._points(featherdrive_sweep.parse_grid(
        "stiffness=1:10:1000,damping=1:10:1000"))) == featherdrive_sweep.MAX_POINTS


class NotAClient:
    pass


@pytest.mark.parametrize("kw,error,match", [
    ({"num_threads": -1}, ValueError, r"num_threads = -1: must be in \[0, 4096\]"),
    ({"num_threads": 10**9}, ValueError, r"num_threads = 1000000000: must be in \[0, 4096\]"),
    ({"num_threads": 1.5}, TypeError, r"num_threads = 1\.5: must be an integer, not float"),
    ({"chunk_size": 0}, ValueError, r"chunk_size = 0: must be in \[1, 1000000\]"),
    ({"chunk_size": 2.5}, TypeError, r"chunk_size = 2\.5: must be an integer or None"),
    ({"client": NotAClient()}, TypeError, r"client = <.*: must be a distributed\.Client or None"),
    ({"joint": 3}, TypeError, r"joint = 3: must be a str or None, not int"),
    ({"scene": 3}, TypeError, r"scene = 3: must be a path"),
    ({"grid": {3: [1]}}, TypeError, r"grid: a name 3 must be a str"),
    ({"grid": {"damping": ["x"]}}, ValueError, r"grid damping: values must be numbers"),
])
def test_bad_arguments_name_the_argument(kw, error, match):
    args = dict(scene=str(SLIDER), grid="damping=1:2:2") | kw
    with pytest.raises(error, match=match):
        fd.sweep(**args)


def test_outputs_never_replace_an_input_and_respect_the_umask(tmp_path, module_dir):
    out = tmp_path / "out"
    out.mkdir()
    scene = slider_copy(out)
    (out / "sweep.csv").symlink_to(scene)  # the scene reached through the output's name
    before = scene.read_text()
    r = subprocess.run([cli(module_dir), "sweep", str(scene), "--grid", "damping=1:2:2",
                        "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert f"--out {out / 'sweep.csv'}: is the scene ({scene}, an input of this run)" in r.stderr
    (out / "sweep.csv").unlink()
    os.link(out / "slider.urdf", out / "sweep.png")
    r = subprocess.run([cli(module_dir), "sweep", str(scene), "--grid", "damping=1:2:2",
                        "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "sweep.png: is the scene's model" in r.stderr, r.stderr
    assert scene.read_text() == before and not (out / "sweep.csv").exists()
    (out / "sweep.png").unlink()
    (out / "sweep.csv").mkdir()
    r = subprocess.run([cli(module_dir), "sweep", str(scene), "--grid", "damping=1:2:2",
                        "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "sweep.csv: is not a regular file; refusing" in r.stderr
    (out / "sweep.csv").rmdir()
    # The run that writes (its plot costs a second) also shows the chosen objective in the
    # summary line (test_the_plot_labels_its_colour_scale_and_axes_with_units: the plot's).
    r = subprocess.run(["sh", "-c", 'umask 027 && exec "$@"', "sh", cli(module_dir), "sweep",
                        str(scene), "--grid", "damping=1:2:2", "--objective", "settling_time",
                        "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    for name in ("sweep.csv", "sweep.png"):
        assert oct((out / name).stat().st_mode & 0o777) == oct(0o640)
    assert "least settling time (largest of the drives): " in r.stdout
    assert " s at damping " in r.stdout


def test_non_regular_scenes_and_threads_on_the_command_line(tmp_path, module_dir):
    fifo = tmp_path / "pipe.yaml"
    os.mkfifo(fifo)
    for args, message in [
        (["/dev/zero"], "/dev/zero: is not a regular file (a character device)"),
        ([str(fifo)], f"{fifo}: is not a regular file (a FIFO)"),
        ([str(SLIDER), "--threads", "-1"], "--threads = -1: must be in [0, 4096]"),
        ([str(SLIDER), "--threads", "1000000000"], "--threads = 1000000000: must be in"),
        ([str(SLIDER), "--threads", "1e9"], "argument --threads: invalid int value: '1e9'"),
    ]:
        r = subprocess.run([cli(module_dir), "sweep", *args, "--grid", "damping=1"],
                           capture_output=True, text=True, timeout=60, cwd=tmp_path)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert message in r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe.yaml"]


# Objectives beside RMS (issue 33): overshoot, settling time, max |drive force|; the edge
# warning; the plot's labels.

def step_scene(folder, k=100.0, A=0.1, dt=1e-3, T=5.0, damping=None):
    """The 2.5 kg slider without gravity, at rest at 0, target A from the first step."""
    gains = f"stiffness: {k}" + (f", damping: {damping}" if damping is not None else "")
    scene = folder / "step.yaml"
    scene.write_text(
        f"model: {ROOT / 'examples' / 'slider.urdf'}\nfixed_base: true\ngravity: [0, 0, 0]\n"
        f"dt: {dt}\nsteps: {round(T / dt)}\nsolver: {{type: pgs}}\n"
        f"drives:\n  slide: {{type: force, {gains}, target_position: {A}}}\n")
    return scene


def test_step_objectives_follow_the_damped_oscillator(tmp_path):
    # x(t) = A (1 - e^(-z w t) (cos wd t + z / sqrt(1 - z^2) sin wd t)), wd = w sqrt(1 - z^2):
    # overshoot exp(-pi z / sqrt(1 - z^2)) of the step; settling time the last time the error
    # leaves the 2 % band (here from the closed form sampled every 10 us). The implicit step's
    # own damping lowers the overshoot a little (measured: 1.0 to 1.4 %).
    k, m, A, dt, T = 100.0, 2.5, 0.1, 1e-3, 5.0
    w, critical = math.sqrt(k / m), 2.0 * math.sqrt(k * m)
    zetas = np.array([0.2, 0.4, 0.6, 0.7])
    result = fd.sweep(str(step_scene(tmp_path)), {"damping": zetas * critical},
                      objective="overshoot")
    assert result.step.tolist() == [True] and result.units == ["m"]
    np.testing.assert_allclose(result.overshoot[:, 0],
                               np.exp(-math.pi * zetas / np.sqrt(1 - zetas ** 2)), rtol=0.02)
    t = np.arange(0.0, T, 1e-5)
    for i, z in enumerate(zetas):
        wd = w * math.sqrt(1 - z * z)
        e = A * np.exp(-z * w * t) * (np.cos(wd * t) + z / math.sqrt(1 - z * z) * np.sin(wd * t))
        settle = t[np.flatnonzero(np.abs(e) > 0.02 * A)[-1]]
        if z >= 0.4:  # where a slightly damper run leaves the band at the same swing
            assert result.settling_time[i, 0] == pytest.approx(settle, abs=5 * dt)
        # The largest force is the first step's: f = k (A - x1) - c v1 with v1 = dt f / m and
        # x1 = dt v1, so f = k A / (1 + (k dt^2 + c dt) / m).
        c = z * critical
        assert result.max_force[i, 0] == pytest.approx(k * A / (1 + (k * dt * dt + c * dt) / m),
                                                        rel=1e-9)
    # The objective is the largest drive's (one drive here): the overshoot, least at the
    # largest damping swept, the grid's edge.
    np.testing.assert_array_equal(result.objective, result.overshoot[:, 0])
    assert result.best() == 3 and "damping = " in result.warning
    assert "is the largest value swept" in result.warning


def trajectory_objectives(csv_path, joint, target):
    """Overshoot, settling time and max |f| from `featherdrive simulate --out`'s CSV, by the
    documented rules: target(t) a function of time; a constant one away from q(0) is a step."""
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["t"]) for r in rows])
    q = np.array([float(r[f"q:{joint}"]) for r in rows])
    force = np.array([float(r[f"f:{joint}"]) for r in rows])
    goal = np.array([target(x) for x in t])
    e = goal - q
    if np.all(goal == goal[0]) and abs(e[0]) > 1e-9:
        overshoot = max(0.0, np.max(-np.sign(e[0]) * e[1:])) / abs(e[0])
        band = 0.02 * abs(e[0])
    else:
        overshoot = np.max(np.abs(e[1:]))
        band = 0.02 * (goal.max() - goal.min())
    outside = np.flatnonzero(np.abs(e) > band)
    settle = (0.0 if outside.size == 0 else math.inf if outside[-1] == len(t) - 1
              else t[outside[-1] + 1])
    return overshoot, settle, np.max(np.abs(force))


@pytest.mark.parametrize("case", ["pendulum_step", "slider_sine"])
def test_objectives_agree_with_simulate_s_trajectory(tmp_path, module_dir, case):
    if case == "pendulum_step":  # revolute, a step from 0 to 0.5 rad without gravity
        joint, grid = "hinge", "stiffness=20:80:2,damping=2:6:2"
        scene_text = (f"model: {ROOT / 'examples' / 'pendulum.urdf'}\ngravity: [0, 0, 0]\n"
                      "dt: 0.002\nsteps: 1500\nsolver: {type: tgs}\n"
                      "drives:\n  hinge: {type: force, stiffness: 80, damping: 2, "
                      "target_position: 0.5}\n")

        def target(t):
            return 0.5
    else:  # prismatic under gravity tracking a sine: overshoot is max |error| [m]
        joint, grid = "slide", "stiffness=100:400:2,damping=10:40:2"
        scene_text = SLIDER.read_text().replace(
            "model: slider.urdf", f"model: {ROOT / 'examples' / 'slider.urdf'}")

        def target(t):
            return 0.1 + 0.2 * math.sin(2 * math.pi * 0.5 * t + 0.3)
    scene = tmp_path / "scene.yaml"
    scene.write_text(scene_text)
    result = fd.sweep(str(scene), grid)
    point = 2  # stiffness high, damping low: the scene's own gains in both cases
    assert (result.step[0], result.units[0]) == ((True, "rad") if case == "pendulum_step"
                                                else (False, "m"))
    traj = tmp_path / "traj.csv"
    s, d = result.points[point]
    text = scene_text.replace("stiffness: 80, damping: 2", f"stiffness: {s}, damping: {d}")
    text = text.replace("stiffness: 400, damping: 40", f"stiffness: {s}, damping: {d}")
    (tmp_path / "point.yaml").write_text(text)
    r = subprocess.run([cli(module_dir), "simulate", str(tmp_path / "point.yaml"), "--out",
                        str(traj)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    overshoot, settle, force = trajectory_objectives(traj, joint, target)
    assert result.overshoot[point, 0] == pytest.approx(overshoot, rel=1e-9)
    assert result.settling_time[point, 0] == pytest.approx(settle, rel=1e-9)
    assert result.max_force[point, 0] == pytest.approx(force, rel=1e-12)
    if case == "pendulum_step":
        assert 0 < overshoot < 1 and 0 < settle < 3.0  # an underdamped step that settles


def test_the_edge_warning_appears_only_when_the_best_point_is_on_the_edge(tmp_path, module_dir):
    # The least RMS error of the step is at z = 1/2 (test_damping_sweep_follows_the_closed_form).
    critical = 2.0 * math.sqrt(100.0 * 2.5)
    scene = step_scene(tmp_path, dt=4e-3, T=2.0)
    inside = fd.sweep(str(scene), {"damping": np.array([0.3, 0.5, 0.8]) * critical})
    assert inside.best() == 1 and inside.warning is None
    edge = fd.sweep(str(scene), {"damping": np.array([0.6, 0.8, 1.0]) * critical,
                                 "stiffness": [100.0]})
    assert edge.best() == 0
    assert edge.warning == (f"the least total rms error is on the grid's edge (damping = "
                            f"{0.6 * critical:.6g} is the least value swept): the optimum may "
                            "lie outside the grid; widen it there")
    for grid, warned in (("damping=4.74:25.3:3", False), ("damping=19:32:3", True)):
        r = subprocess.run([cli(module_dir), "sweep", str(scene), "--grid", grid, "--out",
                            str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stderr
        lines = r.stderr.strip().splitlines()
        assert len(lines) == warned, r.stderr
        if warned:
            assert lines[0].startswith("featherdrive sweep: warning: the least total rms error "
                                       "is on the grid's edge (damping = 19 is the least")


def test_the_plot_labels_its_colour_scale_and_axes_with_units(tmp_path):
    pendulum = tmp_path / "p.yaml"
    pendulum.write_text(f"model: {ROOT / 'examples' / 'pendulum.urdf'}\ndt: 0.01\nsteps: 50\n"
                        "drives:\n  hinge: {type: force, stiffness: 50, damping: 5, "
                        "target_position: 0.3}\n")
    result = fd.sweep(str(pendulum), "stiffness=20:80:2,damping=2:6:2", objective="max_force")
    fig = result.plot(tmp_path / "p.png", "pendulum")
    assert (tmp_path / "p.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    plot, bar = fig.axes
    assert bar.get_ylabel() == "max |drive force| (largest of the drives) [Nm]"
    assert (plot.get_xlabel(), plot.get_ylabel()) == ("damping [Nms/rad]", "stiffness [Nm/rad]")
    for objective, label in (("rms", "total rms error [rad]"),
                             ("overshoot", "overshoot (largest of the drives) "
                                           "[fraction of the step]"),
                             ("settling_time", "settling time (largest of the drives) [s]")):
        other = fd.sweep(str(pendulum), "stiffness=20:80:2,damping=2:6:2", objective=objective)
        assert other.plot(tmp_path / "p.png", "p").axes[1].get_ylabel() == label
        np.testing.assert_array_equal(other.max_force, result.max_force)  # all computed
    # The slider: linear units, and --joint names the drive; one parameter, a curve.
    one = fd.sweep(str(SLIDER), {"damping": [10.0, 40.0]}, joint="slide", objective="overshoot")
    ax = one.plot(tmp_path / "s.png", "s").axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("damping [Ns/m]", "overshoot of slide [m]")
    # The command's summary line names the chosen objective:
    # test_outputs_never_replace_an_input_and_respect_the_umask.


def test_a_bad_objective_is_refused_before_the_run(tmp_path, module_dir):
    with pytest.raises(ValueError, match=r"^objective = 'peak': must be one of rms, overshoot, "
                                         r"settling_time, max_force$"):
        fd.sweep(str(SLIDER), "damping=1", objective="peak")
    with pytest.raises(TypeError, match="objective = 3: must be a str, not int"):
        fd.sweep(str(SLIDER), "damping=1", objective=3)
    r = subprocess.run([cli(module_dir), "sweep", str(SLIDER), "--grid", "damping=1",
                        "--objective", "peak", "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "--objective = 'peak': must be one of rms, overshoot" in r.stderr
    assert not (tmp_path / "o").exists()
