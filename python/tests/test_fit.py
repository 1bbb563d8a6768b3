"""featherdrive_fit (fd.fit, python -m featherdrive_fit): parameters recovered from logs that
featherdrive made with known parameters (the truth the fit never sees), the fitted scene replaying
the log, identical fits on 1 and 2 threads and Dask workers, and one-line errors."""
import csv
import os
import pathlib
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

import featherdrive as fd
import featherdrive_fit
from conftest import ARM

DT = 1.0 / 240.0
ROWS = 301  # 1.25 s
# The noiseless fits of the six gains simulate every row at each evaluation, and those that try
# delays 0, 1 and 2 search once per delay (a short search each, the right one refined): they fit
# a 0.58 s log, which gives the gains back within 1e-12 (measured) as the 1.25 s one does.
SHORT_ROWS = 141


def scene_text(solver="pgs", fit="", delay=0, rows=ROWS):
    return (f"model: {ARM}\nsteps: {rows - 1}\ndt: {DT!r}\n"
            f"solver: {{type: {solver}, position_iterations: 4, velocity_iterations: 1}}\n"
            f"drive_defaults: {{type: force, stiffness: 400, damping: 10, delay: {delay}}}\n"
            "drives: {joint2: {stiffness: 600, damping: 12},\n"
            "         joint4: {stiffness: 300, damping: 6}}\n"
            "joints: {joint2: {armature: 0.08}, joint4: {armature: 0.04}}\n" + fit)


def write(path, text):
    path.write_text(text)
    return path


def chirp_targets(nv, rows=ROWS):
    """0.3 rad chirps from 0.5 to 4 Hz over the rows, a phase apart per joint."""
    t = DT * np.arange(rows)
    phase = 2 * np.pi * (0.5 * t + 3.5 * t ** 2 / (2 * t[-1]))
    return 0.3 * np.sin(phase[:, None] + np.arange(nv)[None, :])


def replay(scene, targets, q0=None):
    """q of the scene's simulation (its drives, delays and joints) under the targets, row k's
    commanded before step k -> k + 1; from q0 if given."""
    sim = fd.make_simulation(scene)
    if q0 is not None:
        sim.set_q(q0)
    q, qd = [sim.q.copy()], [sim.qd.copy()]
    for k in range(len(targets) - 1):
        sim.set_drive_targets(targets[k])
        sim.step()
        q.append(sim.q.copy())
        qd.append(sim.qd.copy())
    return np.array(q), np.array(qd)


def make_log(path, scene, noise=0.0, seed=0, rows=ROWS):
    """Runs the scene (its delay included) on `rows` rows of chirp targets and writes
    featherdrive's CSV columns plus the targets, Gaussian noise of `noise` rad on q."""
    names = scene.model.dof_names
    targets = chirp_targets(len(names), rows)
    q, qd = replay(scene, targets)
    q = q + noise * np.random.default_rng(seed).standard_normal((rows, len(names)))
    write_log(path, names, q, qd, targets)
    return q


def write_log(path, names, q, qd, targets):
    """featherdrive's CSV columns, the targets and a column the fit ignores."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["step", "t"] + [f"q:{n}" for n in names] + [f"qd:{n}" for n in names] +
                   [f"target:{n}" for n in names] + ["comment"])
        for k in range(len(q)):
            w.writerow([k, repr(k * DT)] + [repr(x) for x in q[k]] + [repr(x) for x in qd[k]] +
                       [repr(x) for x in targets[k]] + ["ignored"])


# The starting values are off by 2x (x2 and /2) from the truth of scene_text.
FIT_GAINS = """fit:
  parameters:
    - {quantity: stiffness, joints: [joint2, joint4], bounds: [50, 5000], initial: 1200}
    - {quantity: damping, joints: [joint2], bounds: [0.5, 100], initial: 6}
    - {quantity: damping, joints: [joint4], bounds: [0.5, 100], initial: 12}
    - {quantity: armature, joints: [joint2], bounds: [0.001, 1], initial: 0.04}
    - {quantity: armature, joints: [joint4], bounds: [0.001, 1], initial: 0.08}
    - {quantity: delay, joints: all, bounds: [0, 2]}
"""
TRUTH = {("stiffness", "joint2"): 600, ("stiffness", "joint4"): 300,
         ("damping", "joint2"): 12, ("damping", "joint4"): 6,
         ("armature", "joint2"): 0.08, ("armature", "joint4"): 0.04}


def worst_error(result, truth):
    return max(abs(result.value(q, j) / v - 1) for (q, j), v in truth.items())


@pytest.mark.parametrize("solver", ["pgs", "tgs"])
def test_recovers_gains_armature_and_delay(tmp_path, solver):
    truth_scene = fd.parse_scene(scene_text(solver, delay=1, rows=SHORT_ROWS),
                                 str(tmp_path / "truth.yaml"))
    logged = make_log(tmp_path / "log.csv", truth_scene, rows=SHORT_ROWS)
    scene = write(tmp_path / "fit.yaml", scene_text(solver, FIT_GAINS, rows=SHORT_ROWS))
    result = fd.fit(str(scene), str(tmp_path / "log.csv"), threads=1)
    assert result.delay == 1 and result.converged
    # The wrong delays' short-search costs are far above the right one's: only it is refined.
    assert result.refined_delays == [1], result.table()
    assert re.search(r"cost by delay: 1: \S+; after the short search: 0: \S+, 2: ",
                     result.table()), result.table()
    assert worst_error(result, TRUTH) < 0.01, result.table()
    assert result.rms < 1e-9
    # The fitted scene (drives.J.delay: 1 written in) replays the log.
    text = featherdrive_fit.fitted_scene_text(result, fd.load_scene(str(scene)))
    fitted = fd.parse_scene(text, str(tmp_path / "fitted.yaml"))
    q, _ = replay(fitted, chirp_targets(fitted.model.nv, SHORT_ROWS))
    assert np.abs(q - logged).max() < 1e-9


def test_recovers_friction(tmp_path):
    friction = ("joints: {joint2: {armature: 0.08, friction: {static: 0.6, dynamic: 0.6, "
                "viscous: 0.4}},\n"
                "         joint4: {armature: 0.04, friction: {static: 0.3, dynamic: 0.3, "
                "viscous: 0.2}}}\n")
    text = scene_text().replace(
        "joints: {joint2: {armature: 0.08}, joint4: {armature: 0.04}}\n", friction)
    make_log(tmp_path / "log.csv", fd.parse_scene(text, str(tmp_path / "truth.yaml")))
    fit = """fit:
  parameters:
    - {quantity: friction.dynamic, joints: [joint2, joint4], bounds: [0, 5], initial: 1.2}
    - {quantity: friction.viscous, joints: [joint2, joint4], bounds: [0, 5], initial: 0.2}
"""
    scene = write(tmp_path / "fit.yaml", text + fit)
    result = fd.fit(str(scene), str(tmp_path / "log.csv"), threads=1)
    truth = {("friction.dynamic", "joint2"): 0.6, ("friction.dynamic", "joint4"): 0.3,
             ("friction.viscous", "joint2"): 0.4, ("friction.viscous", "joint4"): 0.2}
    assert worst_error(result, truth) < 0.05, result.table()


def test_recovers_joint_springs(tmp_path):
    springs = ("joints: {joint2: {armature: 0.08, joint_spring: {stiffness: 150, reference: 0.2}},\n"
               "         joint4: {armature: 0.04, joint_spring: {stiffness: 80, damping: 1}}}\n")
    text = scene_text().replace(
        "joints: {joint2: {armature: 0.08}, joint4: {armature: 0.04}}\n", springs)
    logged = make_log(tmp_path / "log.csv", fd.parse_scene(text, str(tmp_path / "truth.yaml")))
    fit = """fit:
  parameters:
    - {quantity: joint_spring.stiffness, joints: [joint2, joint4], bounds: [0, 1000], initial: 300}
    - {quantity: joint_spring.damping, joints: [joint4], bounds: [0, 10], initial: 2}
"""
    scene = write(tmp_path / "fit.yaml", text + fit)
    result = fd.fit(str(scene), str(tmp_path / "log.csv"), threads=1)
    truth = {("joint_spring.stiffness", "joint2"): 150, ("joint_spring.stiffness", "joint4"): 80,
             ("joint_spring.damping", "joint4"): 1}
    assert worst_error(result, truth) < 1e-6, result.table()
    # The fitted scene (joints.J.joint_spring written in) replays the log.
    text = featherdrive_fit.fitted_scene_text(result, fd.load_scene(str(scene)))
    fitted = fd.parse_scene(text, str(tmp_path / "fitted.yaml"))
    q, _ = replay(fitted, chirp_targets(fitted.model.nv))
    assert np.abs(q - logged).max() < 1e-9
    # Bounds the spring's own check refuses are named with the joint.
    bad = scene_text() + fit.replace("bounds: [0, 10]", "bounds: [-1, 10]")
    with pytest.raises(ValueError, match=r"fit.parameters\[1\].bounds = \[-1, 10\]: joint spring "
                                         r"of joint 'joint4': damping = -1 must be finite and >= 0"):
        fd.parse_scene(bad, str(tmp_path / "bad.yaml"))


def test_recovers_mass_scale_and_max_force(tmp_path):
    """link3 1.3 times heavier (its inertia too, Batch.set_link_mass) and joint4's drive limited
    to 20 Nm, which the chirp reaches; fitted from 2 and 40."""
    text = scene_text().replace("joint4: {stiffness: 300, damping: 6}",
                                "joint4: {stiffness: 300, damping: 6, max_force: 20}")
    truth = fd.parse_scene(text, str(tmp_path / "truth.yaml"))
    batch = fd.Batch(fd.make_simulation(truth), 1)
    link = truth.model.link_index("link3")
    batch.set_link_mass(link, 1.3 * truth.model.links[link].mass)
    targets = chirp_targets(truth.model.nv)
    q, qd = [np.array(batch.q[0])], [np.array(batch.qd[0])]
    for k in range(ROWS - 1):
        batch.set_drive_targets(targets[k])
        batch.step()
        q.append(np.array(batch.q[0]))
        qd.append(np.array(batch.qd[0]))
        assert abs(batch.drive_force[0, 3]) <= 20.0 + 1e-9
    write_log(tmp_path / "log.csv", truth.model.dof_names, q, qd, targets)
    fit = """fit:
  parameters:
    - {quantity: mass_scale, links: [link3], bounds: [0.5, 3], initial: 2}
    - {quantity: max_force, joints: [joint4], bounds: [1, 100], initial: 40}
"""
    scene = write(tmp_path / "fit.yaml", text.replace("max_force: 20", "max_force: 40") + fit)
    result = fd.fit(str(scene), str(tmp_path / "log.csv"), threads=1)
    truth = {("mass_scale", "link3"): 1.3, ("max_force", "joint4"): 20.0}
    assert worst_error(result, truth) < 0.01, result.table()


def test_noisy_log_with_segments_and_the_fitted_scene(tmp_path):
    noise = 1e-4
    truth_scene = fd.parse_scene(scene_text(), str(tmp_path / "truth.yaml"))
    clean = make_log(tmp_path / "clean.csv", truth_scene)
    noisy = make_log(tmp_path / "log.csv", truth_scene, noise=noise)
    fit = FIT_GAINS.replace("    - {quantity: delay, joints: all, bounds: [0, 2]}\n",
                            "  data: {segment_steps: 100}\n")
    scene = write(tmp_path / "fit.yaml", scene_text("pgs", fit))
    old = os.umask(0o027)  # the outputs respect the umask (their plot costs seconds: one fit)
    try:
        result = fd.fit(str(scene), str(tmp_path / "log.csv"), threads=1,
                        out=str(tmp_path / "out"))
    finally:
        os.umask(old)
    for path in (result.scene_file, result.plot_file, tmp_path / "out" / "fit_fit.txt"):
        assert oct(os.stat(path).st_mode & 0o777) == oct(0o666 & ~0o027), path
    assert worst_error(result, TRUTH) < 0.03 and result.converged, result.table()
    # The intervals cover the truth (95 %: allow 3 half-widths for the 6 together).
    for e in result.estimates:
        assert abs(e.value - TRUTH[(e.quantity, e.names[0])]) < 3 * e.ci95, result.table()
    # The fitted scene, replayed from the log's start with its targets, matches the clean log
    # within the noise level and the noisy one at the noise level.
    fitted = fd.load_scene(result.scene_file)
    assert fitted.fit is not None and os.path.exists(result.plot_file)
    q, _ = replay(fitted, chirp_targets(fitted.model.nv), q0=noisy[0])  # as the fit starts
    assert np.sqrt(np.mean((q - clean) ** 2)) < noise
    assert 0.9 * noise < np.sqrt(np.mean((q - noisy) ** 2)) < 1.2 * noise
    assert open(tmp_path / "fit.yaml").read() == scene_text("pgs", fit)  # input untouched


def test_a_known_delay_with_segments(tmp_path):
    """The scene's own delay (2 steps, not fitted): each segment starts with the targets that
    were in the pipe, as the uninterrupted run had them."""
    truth_scene = fd.parse_scene(scene_text(delay=2), str(tmp_path / "truth.yaml"))
    make_log(tmp_path / "log.csv", truth_scene)
    fit = FIT_GAINS.replace("    - {quantity: delay, joints: all, bounds: [0, 2]}\n",
                            "  data: {segment_steps: 100}\n")
    scene = write(tmp_path / "fit.yaml", scene_text("pgs", fit, delay=2))
    result = fd.fit(str(scene), str(tmp_path / "log.csv"), threads=1)
    assert worst_error(result, TRUTH) < 1e-6, result.table()
    assert result.rms < 1e-9


def test_a_log_cut_from_running_motion_with_a_delay(tmp_path):
    """The robot runs (delay 2, TGS) for 0.25 s before the log's first row: the targets it
    commanded then are not in the log. The replay starts 2 rows (the largest delay tried) into
    the log, where the targets in the pipe are logged ones; the gains come back within 1 %."""
    truth_scene = fd.parse_scene(scene_text("tgs", delay=2, rows=SHORT_ROWS),
                                 str(tmp_path / "truth.yaml"))
    cut = 60
    sim = fd.make_simulation(truth_scene)
    t = DT * np.arange(cut + SHORT_ROWS)
    targets = 0.3 * np.sin(2 * np.pi * (1.0 + 1.5 * t)[:, None] * t[:, None] +
                           np.arange(sim.model.nv)[None, :])
    q, qd = [sim.q.copy()], [sim.qd.copy()]
    for k in range(cut + SHORT_ROWS - 1):
        sim.set_drive_targets(targets[k])
        sim.step()
        q.append(sim.q.copy())
        qd.append(sim.qd.copy())
    q, qd = np.array(q)[cut:], np.array(qd)[cut:]
    assert np.abs(qd[0]).max() > 0.5  # mid-motion
    write_log(tmp_path / "log.csv", truth_scene.model.dof_names, q, qd, targets[cut:])
    scene = write(tmp_path / "fit.yaml", scene_text("tgs", FIT_GAINS, rows=SHORT_ROWS))
    result = fd.fit(str(scene), str(tmp_path / "log.csv"), threads=1)
    assert result.delay == 2 and result.refined_delays == [2], result.table()
    assert worst_error(result, TRUTH) < 0.01, result.table()
    # Rows before the replay's start have no simulated q.
    assert np.isnan(result.q_fitted[:2]).all() and not np.isnan(result.q_fitted[2:]).any()
    assert result.q_fitted.shape == q.shape
    # A log with no row after the replay's start: one line naming the scene and the rows.
    write_log(tmp_path / "short.csv", truth_scene.model.dof_names, q[:3], qd[:3], targets[:3])
    with pytest.raises(ValueError, match=r"fit\.yaml: the replay starts 2 rows into the log "
                                         r"\(the largest delay\), and the log has 3 rows$"):
        fd.fit(str(scene), str(tmp_path / "short.csv"), threads=1)


def test_a_small_cost_gap_refines_every_close_delay(tmp_path):
    """Noise of 3e-2 rad on q (a tenth of the targets' amplitude) brings the wrong delays' costs
    within 8 % of the right one's: all are refined, and the log's own delay (1) still wins."""
    truth_scene = fd.parse_scene(scene_text(delay=1, rows=SHORT_ROWS), str(tmp_path / "t.yaml"))
    make_log(tmp_path / "log.csv", truth_scene, noise=3e-2, seed=2, rows=SHORT_ROWS)
    # The stiffnesses alone (3 parameter sets per Jacobian, not 7): the same delay search.
    fit = ("fit:\n  parameters:\n"
           "    - {quantity: stiffness, joints: [joint2, joint4], bounds: [50, 5000], "
           "initial: 1200}\n"
           "    - {quantity: delay, joints: all, bounds: [0, 2]}\n")
    scene = write(tmp_path / "fit.yaml", scene_text("pgs", fit, rows=SHORT_ROWS))
    result = fd.fit(str(scene), str(tmp_path / "log.csv"), threads=1)
    costs = result.cost_by_delay
    assert max(costs.values()) < 1.1 * costs[1], result.table()  # the gap is small
    assert result.refined_delays == [0, 1, 2], result.table()
    assert result.delay == 1 and result.converged, result.table()


def test_a_floating_base_is_refused_and_a_ball_joint_fitted_per_axis(tmp_path, module_dir):
    """A floating root's pose is no dof position: refused in one line. The spherical wrist's
    twist stiffness comes back from simulate's own CSV (its q:wrist:twist columns)."""
    floating = write(tmp_path / "floating.yaml", scene_text("pgs", FIT_GAINS) +
                     "fixed_base: false\n")
    truth_scene = fd.parse_scene(scene_text(), str(tmp_path / "truth.yaml"))
    make_log(tmp_path / "log.csv", truth_scene)
    with pytest.raises(ValueError, match="fit: robots with a fixed base are fitted"):
        fd.fit(str(floating), str(tmp_path / "log.csv"))
    wrist = os.path.join(os.path.dirname(ARM), "spherical_wrist.urdf")
    text = (f"model: {wrist}\ndt: 0.0166666667\nsteps: 60\n"
            "solver: {type: tgs, position_iterations: 8, velocity_iterations: 1}\n"
            "initial: {q: {wrist:twist: 0.2, wrist:swing1: -0.1}, qd: {wrist:swing2: 1.0}}\n"
            "drives:\n  shoulder: {type: force, stiffness: 300, damping: 20, target_position: 0.4}\n"
            "  wrist:twist: {type: force, stiffness: STIFF, damping: 1, target_position: 0.4}\n"
            "  wrist:swing1: {type: force, stiffness: 20, damping: 1, target_position: 0.3}\n")
    truth = write(tmp_path / "wrist.yaml", text.replace("STIFF", "20"))
    log = tmp_path / "wrist.csv"
    run = subprocess.run([str(module_dir.parent / "tools" / "featherdrive"),
                          "simulate", str(truth), "--out", str(log)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    guess = write(tmp_path / "guess.yaml", text.replace("STIFF", "30") +
                  "fit: {parameters: [{quantity: stiffness, joints: [wrist:twist], "
                  "bounds: [5, 100]}]}\n")
    result = fd.fit(str(guess), str(log), threads=1)
    assert abs(result.estimates[0].value - 20) < 1e-6 * 20


def test_resampled_log(tmp_path):
    """A log at twice the scene's rate, resampled (linear), recovers what the log at dt does."""
    truth_scene = fd.parse_scene(scene_text(rows=SHORT_ROWS), str(tmp_path / "truth.yaml"))
    make_log(tmp_path / "log.csv", truth_scene, rows=SHORT_ROWS)
    rows = list(csv.reader(open(tmp_path / "log.csv")))
    t = rows[0].index("t")
    fine = [rows[0]] + [r for r in rows[1:]]
    # Insert a midpoint row between each pair: q linear there, the target held.
    out = [fine[0]]
    for a, b in zip(fine[1:-1], fine[2:]):
        out.append(a)
        mid = list(a)
        for i, name in enumerate(rows[0]):
            if name.startswith(("q:", "qd:")) or name == "t":
                mid[i] = repr((float(a[i]) + float(b[i])) / 2)
        out.append(mid)
    out.append(fine[-1])
    with open(tmp_path / "fine.csv", "w", newline="") as f:
        csv.writer(f).writerows(out)
    fit = FIT_GAINS.replace("    - {quantity: delay, joints: all, bounds: [0, 2]}\n",
                            "  data: {resample: linear}\n")
    scene = write(tmp_path / "fit.yaml", scene_text("pgs", fit, rows=SHORT_ROWS))
    result = fd.fit(str(scene), str(tmp_path / "fine.csv"), threads=1)
    assert result.log.t.size == SHORT_ROWS
    assert float(rows[1][t]) == result.log.t[0]
    assert worst_error(result, TRUTH) < 1e-6, result.table()


def fit_with(tmp_path, **kw):
    truth_scene = fd.parse_scene(scene_text(), str(tmp_path / "truth.yaml"))
    make_log(tmp_path / "log.csv", truth_scene, noise=1e-4)
    # Segments of 50 steps: a sixth of the steps per batch (the threads meet at every step).
    fit = FIT_GAINS.replace("    - {quantity: delay, joints: all, bounds: [0, 2]}\n",
                            "  data: {segment_steps: 50}\n")
    scene = write(tmp_path / "fit.yaml", scene_text("pgs", fit))
    result = fd.fit(str(scene), str(tmp_path / "log.csv"), **kw)
    return [e.value.hex() for e in result.estimates] + [result.rms.hex()]


def test_identical_on_1_and_2_threads_and_a_local_cluster(tmp_path):
    one = fit_with(tmp_path, threads=1)
    assert fit_with(tmp_path, threads=2, chunks=3) == one
    import distributed
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        assert fit_with(tmp_path, client=client, threads=1) == one


# Bad input: one line naming the file, the key or column and the value.

def test_bad_logs(tmp_path):
    truth_scene = fd.parse_scene(scene_text(), str(tmp_path / "truth.yaml"))
    make_log(tmp_path / "log.csv", truth_scene)
    scene = write(tmp_path / "fit.yaml", scene_text("pgs", FIT_GAINS))
    rows = list(csv.reader(open(tmp_path / "log.csv")))

    def bad(edit, match):
        edited = [list(r) for r in rows]
        edit(edited)
        with open(tmp_path / "bad.csv", "w", newline="") as f:
            csv.writer(f).writerows(edited)
        with pytest.raises(ValueError, match=match) as e:
            fd.fit(str(scene), str(tmp_path / "bad.csv"))
        assert "\n" not in str(e.value)

    col = rows[0].index("target:joint4")
    bad(lambda r: [row.pop(col) for row in r], r"bad\.csv: missing column target:joint4$")
    bad(lambda r: r[6].__setitem__(1, "0.001"),  # line 7 of the file
        r"bad\.csv: row 7: t = 0\.001 is not after the previous row's 0\.016666666666666666 ")
    bad(lambda r: r[3].__setitem__(3, "nan"), r"bad\.csv: row 4: q:joint2 = nan: must be finite")
    bad(lambda r: [row.__setitem__(1, repr(float(row[1]) * 2)) for row in r[1:]],
        r"bad\.csv: rows 2-3: time step 0\.008333333333333333 s is not the scene's dt "
        r"0\.004166666666666667 s \(set fit\.data\.resample: linear\)")
    qd4 = rows[0].index("qd:joint4")
    bad(lambda r: [row.pop(qd4) for row in r],
        r"bad\.csv: missing column qd:joint4 \(give qd for every joint or none\)$")
    # Segments restart from the logged qd: a log without qd cannot have them.
    write(scene, scene_text("pgs", FIT_GAINS + "  data: {segment_steps: 50}\n"))
    qd_columns = [i for i, name in enumerate(rows[0]) if name.startswith("qd:")]
    bad(lambda r: [row.pop(i) for row in r for i in reversed(qd_columns)],
        r"fit\.yaml: fit\.data\.segment_steps = 50: segments start from the logged qd, and "
        r"the log has no qd columns$")


@pytest.mark.parametrize("entry,match", [
    ("{quantity: stiffness, joints: [elbow], bounds: [1, 2]}",
     r"fit\.parameters\[0\]\.joints\[0\]: no joint named 'elbow' in arm7\.urdf"),
    ("{quantity: damping, joints: [joint2], bounds: [50, 5]}",
     r"fit\.parameters\[0\]\.bounds = \[50, 5\]: lower must be below upper$"),
    ("{quantity: stiffness, joints: [joint2], bounds: [1, 100]}",
     r"fit\.parameters\[0\]: the starting value \(the scene's stiffness of joint2; give "
     r"initial:\) = 600 is outside bounds \[1, 100\]$"),
])
def test_bad_fit_sections(tmp_path, entry, match):
    scene = write(tmp_path / "fit.yaml", scene_text("pgs", f"fit:\n  parameters:\n    - {entry}\n"))
    with pytest.raises(ValueError, match=match):
        fd.load_scene(str(scene))


def test_the_command(tmp_path, module_dir):
    """featherdrive fit: the table and the outputs, exit 0; a bad log or fit: section: one line,
    exit 2, nothing written."""
    command = module_dir.parent / "tools" / "featherdrive"
    assert command.exists(), command
    make_log(tmp_path / "log.csv", fd.parse_scene(scene_text(), str(tmp_path / "t.yaml")))
    fit = "fit:\n  parameters:\n    - {quantity: stiffness, joints: [joint2], bounds: [50, 5000]}\n"
    scene = write(tmp_path / "fit.yaml", scene_text("pgs", fit).replace(
        "joint2: {stiffness: 600", "joint2: {stiffness: 300"))
    run = subprocess.run([str(command), "fit", str(scene), "--data", str(tmp_path / "log.csv"),
                          "--out", str(tmp_path / "out"), "--threads", "1"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "stiffness              joint2                            300          600" in run.stdout
    assert {p.name for p in (tmp_path / "out").iterdir()} == {
        "fit_fitted.yaml", "fit_fit.png", "fit_fit.txt"}
    (tmp_path / "bad.csv").write_text("t,q:joint1\n0,0\n0.1,0\n")
    run = subprocess.run([str(command), "fit", str(scene), "--data", str(tmp_path / "bad.csv")],
                         capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 2
    assert run.stderr == f"featherdrive fit: {tmp_path / 'bad.csv'}: missing column q:joint2\n"
    assert not (tmp_path / "out" / f"{pathlib.Path(scene).stem}_fit").exists()
    # python -m featherdrive_fit, which the command runs: a bad fit: section, one line, exit 2.
    write(scene, scene_text("pgs", fit.replace("[50, 5000]", "[5000, 50]")))
    run = subprocess.run([sys.executable, "-m", "featherdrive_fit", str(scene), "--data",
                          str(tmp_path / "log.csv")], capture_output=True, text=True, cwd=tmp_path,
                         env=dict(os.environ, PYTHONPATH=str(module_dir)))
    assert run.returncode == 2
    assert run.stderr == (f"featherdrive fit: {scene}: fit.parameters[0].bounds = [5000, 50]: "
                          "lower must be below upper\n")
    assert not (tmp_path / "out" / f"{pathlib.Path(scene).stem}_fit").exists()


# Hardening (issue 36): the C++ commands' input and output rules, numbers as the C++ readers
# take them, bounds on what a log makes, arguments checked before work, MJCF includes.

def small_fit(tmp_path, fit="fit:\n  parameters:\n    - {quantity: stiffness, joints: [joint2], "
                            "bounds: [50, 5000]}\n"):
    make_log(tmp_path / "log.csv", fd.parse_scene(scene_text(), str(tmp_path / "t.yaml")))
    return write(tmp_path / "fit.yaml", scene_text("pgs", fit)), tmp_path / "log.csv"


def test_logs_that_are_not_regular_files_are_refused_unread(tmp_path):
    scene, _ = small_fit(tmp_path)
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    for data, why in (("/dev/zero", "is not a regular file (a character device)"),
                      (str(fifo), "is not a regular file (a FIFO)"),
                      (str(tmp_path), "is a directory")):
        with pytest.raises(ValueError, match="^" + re.escape(f"{data}: {why}")):
            fd.fit(str(scene), data)
    big = tmp_path / "big.csv"
    with open(big, "wb") as f:
        f.truncate(fd.MAX_INPUT_BYTES + 1)  # sparse
    with pytest.raises(ValueError,
                       match=rf"big\.csv: is larger than 64 MiB \({fd.MAX_INPUT_BYTES + 1} "):
        fd.fit(str(scene), str(big))


def test_log_numbers_are_decimal_and_text_is_utf8(tmp_path):
    scene, log = small_fit(tmp_path)
    rows = log.read_text().splitlines()
    header = rows[0].split(",")
    col = header.index("q:joint3")

    def edited(row, value):
        fields = rows[row].split(",")
        fields[col] = value
        return "\n".join(rows[:row] + [",".join(fields)] + rows[row + 1:]) + "\n"

    # Python's float() takes each of these; the C++ readers take none.
    for text in ("1_0", " 1", "0x10", "infinity", "1e5_0"):
        (tmp_path / "bad.csv").write_text(edited(3, text))
        with pytest.raises(ValueError, match=r"bad\.csv: row 4: q:joint3 = "):
            fd.fit(str(scene), str(tmp_path / "bad.csv"))
    # A byte order mark is no part of the first column's name: the fit reads the log as without.
    (tmp_path / "bom.csv").write_bytes(b"\xef\xbb\xbf" + log.read_bytes())
    assert fd.fit(str(scene), str(tmp_path / "bom.csv")).rms == fd.fit(str(scene), str(log)).rms
    # Not UTF-8: the line and the byte offset of the first bad byte.
    data = log.read_bytes()
    offset = data.index(b"\n", data.index(b"\n") + 1) + 3  # in the third line
    (tmp_path / "latin.csv").write_bytes(data[:offset] + b"\xe9" + data[offset + 1:])
    with pytest.raises(ValueError, match=rf"latin\.csv: line 3, byte offset {offset}: byte 0xe9 "
                                         "is not UTF-8"):
        fd.fit(str(scene), str(tmp_path / "latin.csv"))
    # A field longer than csv's limit: one line naming the line and the column.
    (tmp_path / "long.csv").write_text(edited(2, '"' + "1" * 200_000 + '"'))
    with pytest.raises(ValueError, match=rf"long\.csv: line 3, column {col + 1} \(q:joint3\): "
                                         "a field of 200002 characters"):
        fd.fit(str(scene), str(tmp_path / "long.csv"))


def test_resampled_length_is_bounded_before_it_is_made(tmp_path):
    fit = ("fit:\n  data: {resample: linear}\n  parameters:\n"
           "    - {quantity: stiffness, joints: [joint2], bounds: [50, 5000]}\n")
    scene, log = small_fit(tmp_path, fit)
    rows = log.read_text().splitlines()
    fields = rows[-1].split(",")
    fields[1] = "1.7e9"  # one time stamp in seconds since 1970: 4e11 steps of dt
    (tmp_path / "bad.csv").write_text("\n".join(rows[:-1] + [",".join(fields)]) + "\n")
    steps = 1.7e9 / DT
    with pytest.raises(ValueError, match=rf"bad\.csv: row {len(rows)}: t = 1700000000\.0 is "
                                         r"1\.7e\+09 s after the first row: "
                                         rf"{re.escape(f'{steps:.4g}')} steps of "
                                         rf"dt = .* more than {featherdrive_fit.MAX_LOG_STEPS}"):
        fd.fit(str(scene), str(tmp_path / "bad.csv"))


def test_starting_at_the_truth_stays_there_and_unscalable_ranges_are_refused(tmp_path):
    # From the truth (600 N m/rad, 12 N m s/rad), bounds up to 1e308 are no reason to move.
    fit = ("fit:\n  parameters:\n"
           "    - {quantity: stiffness, joints: [joint2], bounds: [0, 1e308]}\n"
           "    - {quantity: damping, joints: [joint2], bounds: [0, 1e308]}\n")
    scene, log = small_fit(tmp_path, fit)
    result = fd.fit(str(scene), str(log), threads=1)
    assert result.value("stiffness", "joint2") == pytest.approx(600, rel=1e-9)
    assert result.value("damping", "joint2") == pytest.approx(12, rel=1e-9)
    # An unknown starting at 0 has only its range for a scale: the fit would start 1e-10 of it
    # inside the bounds, 1e298 for [0, 1e308].
    zero = "fit:\n  parameters:\n    - {quantity: friction_coefficient, joints: [joint2], bounds: "
    write(scene, scene_text("pgs", zero + "[0, 1e308]}\n"))
    with pytest.raises(ValueError, match=r"fit\.yaml: fit\.parameters\[0\]: starts at 0 with "
                                         r"bounds \[0, 1e\+308\]: .* at most 1e\+06; give "
                                         r"initial: \(not 0\) or narrower bounds$"):
        fd.fit(str(scene), str(log), threads=1)
    write(scene, scene_text("pgs", zero + "[0, 10]}\n"))
    assert abs(fd.fit(str(scene), str(log), threads=1).estimates[0].value) <= 1e-9 * 10


class NotAClient:
    pass


@pytest.mark.parametrize("kw,error,match", [
    ({"threads": -1}, ValueError, r"threads = -1: must be in \[0, 4096\]"),
    ({"threads": 10**9}, ValueError, r"threads = 1000000000: must be in \[0, 4096\]"),
    ({"threads": 1.5}, TypeError, r"threads = 1\.5: must be an integer or None, not float"),
    ({"threads": True}, TypeError, r"threads = True: must be an integer or None, not bool"),
    ({"chunks": 0}, ValueError, r"chunks = 0: must be in \[1, 4096\]"),
    ({"chunks": -5}, ValueError, r"chunks = -5: must be in \[1, 4096\]"),
    ({"chunks": 2.5}, TypeError, r"chunks = 2\.5: must be an integer or None, not float"),
    ({"client": NotAClient()}, TypeError, r"client = <.*: must be a "
                                          r"distributed\.Client or None, not NotAClient"),
    ({"out": 3}, TypeError, r"out = 3: must be a path \(str or os\.PathLike\) or None, not int"),
    ({"data": 3}, TypeError, r"data = 3: must be a path"),
    ({"scene": None}, TypeError, r"scene = None: must be a path"),
    ({"verbose": "yes"}, TypeError, r"verbose = 'yes': must be a bool"),
])
def test_bad_arguments_name_the_argument_before_any_work(tmp_path, kw, error, match):
    scene, log = small_fit(tmp_path)
    args = dict(scene=str(scene), data=str(log), out=str(tmp_path / "out")) | kw
    with pytest.raises(error, match=match):
        fd.fit(**args)
    assert not (tmp_path / "out").exists()


def test_outputs_are_checked_before_the_fit(tmp_path, monkeypatch):
    scene, log = small_fit(tmp_path)
    ran = []
    monkeypatch.setattr(featherdrive_fit, "read_log", lambda *a: ran.append(a))
    out = tmp_path / "out"
    out.mkdir()
    cases = [  # (out, a file placed there, message)
        (tmp_path / "file", None, r"out .*file: exists and is not a folder"),
        (out, "fit_fit.txt/", r"out .*fit_fit\.txt: is not a regular file; refusing to replace"),
        (tmp_path, None, None),  # out holding the scene: its outputs are other names
    ]
    (tmp_path / "file").write_text("x")
    (out / "fit_fit.txt").mkdir()
    for folder, _, match in cases[:2]:
        with pytest.raises(ValueError, match=match):
            fd.fit(str(scene), str(log), out=str(folder))
    # The fitted scene's name is an input (the scene itself, or the log): never replaced.
    (out / "fit_fit.txt").rmdir()
    shutil.copy(scene, out / "fit.yaml")
    os.link(log, out / "fit_fit.png")
    before = (out / "fit.yaml").read_text()
    with pytest.raises(ValueError, match=r"out .*fit_fit\.png: is the log \(.*log\.csv, an input "
                                         r"of this run\); refusing to overwrite it"):
        fd.fit(str(out / "fit.yaml"), str(log), out=str(out))
    os.unlink(out / "fit_fit.png")
    os.symlink(out / "fit.yaml", out / "fit_fitted.yaml")
    with pytest.raises(ValueError, match=r"fit_fitted\.yaml: is the scene"):
        fd.fit(str(out / "fit.yaml"), str(log), out=str(out))
    assert ran == [] and (out / "fit.yaml").read_text() == before


# The outputs' permissions under a umask: test_noisy_log_with_segments_and_the_fitted_scene.


MJCF_MAIN = '<mujoco model="pendulum"><include file="parts/body.xml"/></mujoco>\n'
MJCF_BODY = ('<mujoco><worldbody><body name="b"><joint name="j" type="hinge" axis="0 1 0"/>'
             '<geom type="capsule" size="0.05" fromto="0 0 0 0 0 -0.5" mass="1"/></body>'
             '</worldbody></mujoco>\n')


def test_an_mjcf_model_with_includes_is_fitted_where_it_is(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "main.xml").write_text(MJCF_MAIN)
    (tmp_path / "parts" / "body.xml").write_text(MJCF_BODY)
    base = (f"model: main.xml\ndt: {DT!r}\nsteps: 100\n"
            "drives: {j: {type: force, stiffness: 50, damping: 2}}\n")
    truth = fd.parse_scene(base, str(tmp_path / "truth.yaml"))
    sim = fd.make_simulation(truth)
    q, qd = [sim.q.copy()], [sim.qd.copy()]
    targets = 0.5 * np.sin(np.arange(101) * DT * 8 * np.pi)
    for k in range(100):
        sim.set_drive_targets(targets[k:k + 1])
        sim.step()
        q.append(sim.q.copy())
        qd.append(sim.qd.copy())
    write_log(tmp_path / "log.csv", ["j"], np.array(q), np.array(qd), targets[:, None])
    fit = ("fit:\n  parameters:\n"
           "    - {quantity: stiffness, joints: [j], bounds: [1, 500], initial: 20}\n")
    scene = write(tmp_path / "fit.yaml", base + fit)
    result = fd.fit(str(scene), str(tmp_path / "log.csv"), threads=1)
    assert result.value("stiffness", "j") == pytest.approx(50, rel=1e-6)
    # Where the files are not (a worker without them), the robot's files are written under a
    # temporary folder that mirrors their paths: the include is found there too once listed.
    job_files = {str(tmp_path / "main.xml"): MJCF_MAIN.encode(),
                 str(tmp_path / "parts" / "body.xml"): MJCF_BODY.encode()}
    moved = {p.replace(str(tmp_path), str(tmp_path / "elsewhere")): d for p, d in job_files.items()}
    text = f"model: {tmp_path / 'elsewhere' / 'main.xml'}\n" + base.split("\n", 1)[1]
    s = featherdrive_fit._scene_from_files(text, str(tmp_path / "elsewhere" / "s.yaml"), moved)
    assert s.model.dof_names == ["j"] and not (tmp_path / "elsewhere").exists()


def test_the_command_refuses_before_work(tmp_path, module_dir):
    """featherdrive fit: a log or scene that is not a regular file, --out onto a file, bad
    --threads: one line, exit 2, no hang, nothing written."""
    command = str(module_dir.parent / "tools" / "featherdrive")
    scene, log = small_fit(tmp_path)
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    (tmp_path / "file").write_text("x")
    for args, message in [
        ([str(scene), "--data", "/dev/zero"], "/dev/zero: is not a regular file (a character "
                                              "device)"),
        ([str(scene), "--data", str(fifo)], f"{fifo}: is not a regular file (a FIFO)"),
        ([str(fifo), "--data", str(log)], f"{fifo}: is not a regular file (a FIFO)"),
        ([str(scene), "--data", str(log), "--out", str(tmp_path / "file")],
         f"out {tmp_path / 'file'}: exists and is not a folder"),
        ([str(scene), "--data", str(log), "--out", str(tmp_path), "--threads", "-1"],
         "threads = -1: must be in [0, 4096]"),
        ([str(scene), "--data", str(log), "--threads", "1e9"],
         "argument --threads: invalid int value: '1e9'"),
    ]:
        r = subprocess.run([command, "fit", *args], capture_output=True, text=True, timeout=60,
                           cwd=tmp_path)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert message in r.stderr, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "fit.yaml", "log.csv",
                                                          "pipe.csv"]
