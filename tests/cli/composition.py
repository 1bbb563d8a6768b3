#!/usr/bin/python3
"""Every face on every kind of robot (issue 33): simulate's summary and CSV, checkpoints, the
Python API, Batch, fit, sweep, view, translate both ways, compare-mujoco and compare-physx, on a
corpus that covers every joint kind and base (docs/testing.md, "The composition matrix"). Each
face is checked against an expectation it does not compute itself: the CSV's columns, a run
without the face, the identity of a round trip, or the other engine.

usage: composition.py FEATHERDRIVE SOURCE_DIR OUT_DIR PYTHON_DIR [physx]
"""
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys

import numpy as np

failures = []
CLI = SOURCE = OUT = None
PHYSX = False

# name: (scene, steps). Steps are kept short: the test is about the faces agreeing, not physics.
CORPUS = {
    "arm7": ("examples/arm7_pgs.yaml", 60),
    "spherical_wrist": ("examples/spherical_wrist.yaml", 60),
    "mimic_gripper": ("tests/data/composition/mimic_gripper.yaml", 60),
    "humanoid_fixed": ("examples/humanoid_hold.yaml", 40),
    "humanoid_floating": ("tests/data/composition/humanoid_floating.yaml", 40),
    "wam": ("tests/data/composition/wam.yaml", 60),
    "atlas_floating": ("tests/data/composition/atlas_floating.yaml", 40),
}
# Robots whose scene has a drive on a joint that fit and sweep can vary in a short run.
# What a face refuses, by design, on a robot of the corpus: exit 2 and one line saying why
# (docs/testing.md, "The composition matrix").
REFUSED = {
    ("spherical_wrist", "compare-mujoco"): "is spherical",
    ("humanoid_floating", "compare-mujoco"): "fixed_base = false",
    ("atlas_floating", "compare-mujoco"): "fixed_base = false",
    ("mimic_gripper", "compare-physx"): "no mimic joints",
}
FIT_JOINT = {"arm7": "joint2", "spherical_wrist": "wrist:twist", "mimic_gripper": "left_finger"}
# Robots whose scene cli.compare_physx (tests/cli/compare_physx.py) already runs against PhysX
# for all its steps, with q, qd and force each within 1e-4 of the run's scale: their
# compare-physx cell here would repeat it on a prefix of the same run.
PHYSX_IN_COMPARE_PHYSX = {"arm7": "examples/arm7_pgs.yaml",
                          "humanoid_fixed": "examples/humanoid_hold.yaml"}


def refused(name, face, result):
    """True where the face refuses the robot by design, checked to say so in one line."""
    why = REFUSED.get((name, face))
    if why is None:
        return False
    lines = result.stderr.strip().splitlines()  # an MJCF import's warnings come first
    check(result.returncode == 2 and lines and why in lines[-1] and
          all(l.startswith("featherdrive: warning:") for l in lines[:-1]),
          f"{name}: {face} refuses it in one line saying {why!r}", result)
    return True


def check(condition, what, result=None):
    if not condition:
        detail = ""
        if result is not None:
            detail = f"\n  rc={result.returncode} stdout={result.stdout[-2000:]!r} " \
                     f"stderr={result.stderr[-2000:]!r}"
        failures.append(what + detail)
    return condition


def run(*args, timeout=300):
    return subprocess.run([CLI, *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header = rows[0]
    return header, np.array([[float(v) for v in r] for r in rows[1:]])


def column(header, data, name):
    return data[:, header.index(name)]


def tracking_error(header, data, joint):
    """target - position after each step, from the CSV: row k's target is the command of the
    step from row k to row k + 1 (docs/fitting.md), so step k's error is target[k-1] - q[k]."""
    target = column(header, data, "target:" + joint)
    return target[:-1] - column(header, data, "q:" + joint)[1:]


def summary_rows(stdout):
    """{joint: (final error, rms error)} from simulate's table, whose columns are: joint, drive,
    final error, rms error, then the rest."""
    lines = stdout.splitlines()
    start = next(i for i, l in enumerate(lines) if "final error" in l)
    header = lines[start]
    check(header.index("final error") < header.index("rms error"),
          f"the summary's columns: {header!r}")
    table = {}
    for line in lines[start + 1:]:
        cells = line.split()
        if not line.startswith("  ") or len(cells) < 4 or cells[0] == "wall":
            break
        table[cells[0]] = (float(cells[2]), float(cells[3]))
    return table


def simulate_face(name, scene, steps, work):
    """simulate's CSV and summary: the final and RMS errors the summary prints equal target - q
    of the CSV's own columns; checkpoints: a run stopped and resumed ends on the same bits."""
    out = os.path.join(work, "run.csv")
    r = run("simulate", scene, "--steps", steps, "--out", out)
    if not check(r.returncode == 0, f"{name}: simulate", r):
        return None
    header, data = read_csv(out)
    check(data.shape[0] == steps + 1, f"{name}: the CSV has {steps + 1} rows")
    table = summary_rows(r.stdout)
    targets = [h[len("target:"):] for h in header if h.startswith("target:")]
    check(len(targets) > 0 and set(targets) == set(table),
          f"{name}: the CSV's target columns {targets} are the summary's joints {list(table)}", r)
    for joint in targets:
        if joint not in table:
            continue
        error = tracking_error(header, data, joint)
        final, rms = table[joint]
        expected_rms = math.sqrt(np.mean(error ** 2))
        # The summary prints 4 significant digits.
        check(abs(final - error[-1]) <= 1e-3 * abs(error[-1]) + 1e-9,
              f"{name}: {joint}: summary's final error {final} is the CSV's {error[-1]:.6g}")
        check(abs(rms - expected_rms) <= 1e-3 * expected_rms + 1e-9,
              f"{name}: {joint}: summary's RMS error {rms} is the CSV's {expected_rms:.6g}")
    # Checkpoint at the middle, then the rest: the same last row, digit for digit.
    half = steps // 2
    state = os.path.join(work, "half.state")
    r = run("simulate", scene, "--steps", half, "--save-state", state)
    check(r.returncode == 0, f"{name}: simulate --save-state", r)
    rest = os.path.join(work, "rest.csv")
    r = run("simulate", scene, "--load-state", state, "--steps", steps - half, "--out", rest)
    if check(r.returncode == 0, f"{name}: simulate --load-state", r):
        with open(out) as a, open(rest) as b:
            check(a.read().splitlines()[-1] == b.read().splitlines()[-1],
                  f"{name}: a run checkpointed at step {half} ends on the same bits")
    return header, data


def python_face(fd, name, scene_path, steps, header, data):
    """The Python API's run of the scene equals the CLI's CSV (q of every 1-dof joint and the
    root, bit for bit through the CSV's 17 digits); Batch's environments equal a lone
    Simulation bit for bit without SIMD lanes, within 1e-12 in them."""
    scene = fd.load_scene(scene_path)
    sim = fd.make_simulation(scene)
    for k in range(steps):
        fd.apply_targets(scene, sim, k)
        sim.step()
    model = scene.model
    worst = 0.0
    for link in model.links:
        if link.nq == 1:
            worst = max(worst, abs(sim.q[link.q_index] - column(header, data,
                                                                  "q:" + link.joint_name)[-1]))
    check(worst == 0.0, f"{name}: the Python run's 1-dof q equal the CSV's (worst {worst:.3g})")
    # Batch: three environments, the second with other targets; 0 and 2 equal a lone run.
    lone = fd.make_simulation(scene)
    for k in range(10):
        lone.step()
    for lanes in (False, True):
        batch = fd.Batch(fd.make_simulation(scene), 3)
        batch.lanes = lanes
        batch.step(10)
        worst = max(max(np.max(np.abs(batch.q[e] - lone.q)), np.max(np.abs(batch.qd[e] - lone.qd)))
                    for e in range(3))
        path = batch.step_path
        check(worst <= (1e-12 if lanes else 0.0),
              f"{name}: Batch's environments ({path}) equal a lone Simulation "
              f"{'within 1e-12' if lanes else 'bit for bit'} (worst {worst:.3g})")


def fit_face(name, scene_path, steps, work, header, data):
    """fit recovers a drive's stiffness from simulate's own CSV (made with the scene's value)."""
    joint = FIT_JOINT[name]
    import yaml
    with open(scene_path) as f:
        scene = yaml.safe_load(f)
    truth = scene["drives"][joint]["stiffness"]
    scene["drives"][joint] = dict(scene["drives"][joint], stiffness=truth * 1.3)
    scene["fit"] = {"parameters": [{"quantity": "stiffness", "joints": [joint],
                                    "bounds": [truth * 0.2, truth * 5]}]}
    fit_scene = os.path.join(work, "fit.yaml")
    with open(fit_scene, "w") as f:
        yaml.safe_dump(scene, f)
    out = os.path.join(work, "fit")
    r = run("fit", fit_scene, "--data", os.path.join(work, "run.csv"), "--out", out,
            "--threads", "1")
    if refused(name, "fit", r) or not check(r.returncode == 0, f"{name}: fit reads simulate's CSV", r):
        return
    fitted = None
    for path in os.listdir(out):
        if path.endswith((".yaml", ".yml")):
            with open(os.path.join(out, path)) as f:
                fitted_scene = yaml.safe_load(f)
            try:
                fitted = float(fitted_scene["drives"][joint]["stiffness"])
            except (KeyError, TypeError):
                pass
    check(fitted is not None and abs(fitted - truth) <= 1e-4 * truth,
          f"{name}: fit recovers {joint}'s stiffness {truth} (got {fitted})", r)


def sweep_face(name, scene_path, work, header, data):
    """sweep's RMS at the scene's own gains equals the RMS of simulate's CSV."""
    joint = FIT_JOINT[name]
    import yaml
    with open(scene_path) as f:
        scene = yaml.safe_load(f)
    k = scene["drives"][joint]["stiffness"]
    c = scene["drives"][joint]["damping"]
    out = os.path.join(work, "sweep")
    r = run("sweep", scene_path, "--grid", f"stiffness={k}:{2 * k}:2,damping={c}:{c}:1",
            "--joint", joint, "--out", out)
    if not check(r.returncode == 0, f"{name}: sweep", r):
        return
    with open(os.path.join(out, "sweep.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    row = min(rows, key=lambda r: abs(float(r["stiffness"]) - k))
    rms_key = "rms:" + joint
    expected = math.sqrt(np.mean(tracking_error(header, data, joint) ** 2))
    got = float(row[rms_key])
    check(abs(got - expected) <= 1e-9 * expected + 1e-12,
          f"{name}: sweep's RMS of {joint} at the scene's gains {got} is the CSV's {expected}")


def view_face(name, scene_path, work, header, data):
    """view's page carries q of every driven joint as the CSV has it."""
    page = os.path.join(work, "page.html")
    r = run("view", scene_path, "--csv", os.path.join(work, "run.csv"), "--out", page)
    if r.returncode == 1 and "node" in r.stderr + r.stdout:
        return  # the page's bundle needs node at build time
    if not check(r.returncode == 0, f"{name}: view", r):
        return
    with open(page) as f:
        text = f.read()
    match = re.search(r'<script[^>]*id="fd-data"[^>]*>(.*?)</script>', text, re.S)
    if not check(match is not None, f"{name}: the page has its data"):
        return
    page_data = json.loads(match.group(1))
    joints = {j["name"]: j for j in page_data["joints"]}
    for h in header:
        if not h.startswith("target:"):
            continue
        joint = h[len("target:"):]
        if not check(joint in joints and joints[joint].get("q") is not None,
                     f"{name}: view draws a curve of {joint}"):
            continue
        q = np.array(joints[joint]["q"])
        expected = column(header, data, "q:" + joint)
        check(q.shape == expected.shape and np.max(np.abs(q - expected)) <= 1e-8,
              f"{name}: view's q of {joint} is the CSV's")


def translate_face(name, scene_path, steps, work, header, data):
    """translate --to mujoco, then --to physx: the scene that comes back runs the same."""
    xml = os.path.join(work, "robot.xml")
    r = run("translate", scene_path, "--to", "mujoco", "--out", xml)
    if not check(r.returncode == 0, f"{name}: translate --to mujoco", r):
        return
    back = os.path.join(work, "back.yaml")
    r = run("translate", xml, "--to", "physx", "--out", back)
    if not check(r.returncode == 0, f"{name}: translate --to physx", r):
        return
    again = os.path.join(work, "again.csv")
    r = run("simulate", back, "--steps", steps, "--out", again)
    if not check(r.returncode == 0, f"{name}: simulate the round trip's scene", r):
        return
    h2, d2 = read_csv(again)
    qs = [h for h in header if h.startswith("q:")]
    scale = max(1e-3, float(np.max(np.abs(data[:, [header.index(h) for h in qs]]))))
    worst = max((np.max(np.abs(column(header, data, h) - column(h2, d2, h)))
                 for h in qs if h in h2), default=math.inf)
    check(set(qs) <= set(h2) and worst <= 1e-9 * scale,
          f"{name}: the round trip's run equals the scene's (worst {worst:.3g} of {scale:.3g})")


def compare_faces(name, scene_path, steps):
    """compare-mujoco and compare-physx run and name every driven joint."""
    r = run("compare-mujoco", scene_path, "--steps", steps)
    if not refused(name, "compare-mujoco", r):
        check(r.returncode == 0, f"{name}: compare-mujoco", r)
    if PHYSX and name not in PHYSX_IN_COMPARE_PHYSX:
        r = run("compare-physx", scene_path, "--steps", steps)
        if refused(name, "compare-physx", r) or not check(r.returncode == 0,
                                                          f"{name}: compare-physx", r):
            return
        # PhysX runs in float32: its q agrees to about 1e-6 of the run's scale on these robots.
        m = re.search(r"largest relative difference: q (\S+), qd (\S+), force (\S+)", r.stdout)
        if check(m is not None, f"{name}: compare-physx prints the relative differences", r):
            q, qd, force = (float(v.rstrip(",")) for v in m.groups())
            print(f"{name}: PhysX relative differences q {q:.2g}, qd {qd:.2g}, force {force:.2g}")
            check(q <= 1e-4, f"{name}: featherdrive's q agrees with PhysX's within 1e-4 of the "
                  f"scale ({q:.2g})", r)


def short_scene(path, steps, work):
    """The scene with `steps` steps and its model's absolute path, in work/scene.yaml: every face
    (sweep and fit use the scene's steps) runs the same steps."""
    import yaml
    with open(path) as f:
        scene = yaml.safe_load(f)
    if not os.path.isabs(scene["model"]):
        scene["model"] = os.path.normpath(os.path.join(os.path.dirname(path), scene["model"]))
    scene["steps"] = steps
    out = os.path.join(work, "scene.yaml")
    with open(out, "w") as f:
        yaml.safe_dump(scene, f)
    return out


def main():
    global CLI, SOURCE, OUT, PHYSX
    CLI, SOURCE, OUT, python_dir = sys.argv[1:5]
    SOURCE = os.path.abspath(SOURCE)
    PHYSX = len(sys.argv) > 5 and sys.argv[5] == "physx"
    sys.path.insert(0, python_dir)
    import featherdrive as fd
    shutil.rmtree(OUT, ignore_errors=True)
    os.makedirs(OUT)
    only = os.environ.get("COMPOSITION_ONLY")
    for name, scene in PHYSX_IN_COMPARE_PHYSX.items():
        check(CORPUS[name][0] == scene, f"{name}: cli.compare_physx runs {scene}, the corpus "
              f"{CORPUS[name][0]}")
    for name, (scene, steps) in CORPUS.items():
        if only and name not in only.split(","):
            continue
        work = os.path.join(OUT, name)
        os.makedirs(work)
        scene_path = short_scene(os.path.join(SOURCE, scene), steps, work)
        before = len(failures)
        result = simulate_face(name, scene_path, steps, work)
        if result is None:
            continue
        header, data = result
        faces = [lambda: python_face(fd, name, scene_path, steps, header, data)]
        if name in FIT_JOINT:
            faces += [lambda: fit_face(name, scene_path, steps, work, header, data),
                      lambda: sweep_face(name, scene_path, work, header, data)]
        faces += [lambda: view_face(name, scene_path, work, header, data),
                  lambda: translate_face(name, scene_path, steps, work, header, data),
                  lambda: compare_faces(name, scene_path, steps)]
        for face in faces:
            try:
                face()
            except Exception as e:  # a face that breaks is one failure; the others still run
                failures.append(f"{name}: {type(e).__name__}: {e}")
        print(f"{name}: {'ok' if len(failures) == before else 'FAILED'}")
    for f in failures:
        print("FAIL:", f)
    print(f"composition: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
