#!/usr/bin/python3
"""simulate's summary and CSV on a ball joint and a floating base, fit reading simulate's log, and
the summary's shares of steps at a bound, each against an independent expectation:

- the summary's final / RMS / max error of each drive is target - the CSV's q column (the target
  from the scene's closed form), for spherical_wrist fixed and on a floating base;
- fit recovers from `simulate --out` the gains that made the log;
- a slider whose damping drive chases 1 m/s with max_force 4 N (m = 2.5 kg, dt = 1/60 s, no
  gravity) gains 4/60/2.5 m/s per step while saturated: saturated in steps 1..37 of 60 (v after
  37 steps 0.987 < 1), and with max_velocity 0.5 the velocity limit acts from step 19
  (19 * 0.02667 > 0.5) on: 42 of 60 steps;
- PGS 4/1 on the arm warns that the drives have not converged, 64 iterations do not;
- an implicit actuator (integration: implicit) at kp dt^2 / m = 100, where the explicit law
  diverges, is named `actuator(implicit)` in the summary and its CSV is implicit Euler of the law
  (docs/math/implicit_actuators.md eq. I3), its force column m (v1 - v0) / dt.

usage: faces.py FEATHERDRIVE SOURCE_DIR OUT_DIR
"""
import csv
import math
import os
import re
import subprocess
import sys

failures = []


def run(*args):
    return subprocess.run(list(args), capture_output=True, text=True, timeout=300)


def check(condition, what, result=None):
    if not condition:
        detail = f"\n  rc={result.returncode} stdout={result.stdout!r} stderr={result.stderr!r}" if result else ""
        failures.append(what + detail)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: [float(r[i]) for r in rows[1:]] for i, name in enumerate(rows[0])}


def table(stdout):
    """The summary's per-drive rows: {joint: [final, rms, max error, max force, 3 shares]}."""
    rows, on = {}, False
    for line in stdout.splitlines():
        words = line.split()
        if words[:2] == ["joint", "drive"]:
            on = True
            continue
        if on and len(words) >= 9 and not line.startswith("  wall"):
            tail = " ".join(words[6:])  # the shares: "12.5 %" or "-" each
            rows[words[0]] = words[2:6] + re.findall(r"-|[0-9.]+ %", tail)
        elif on:
            on = False
    return rows


def wrist_target(joint, t):
    constant = {"shoulder": 0.4, "wrist:twist": 0.4, "wrist:swing1": 0.3}
    return constant[joint] if joint in constant else 0.5 * math.sin(2 * math.pi * 0.5 * t)


def summary_is_the_csv(cli, scene, out, tag):
    r = run(cli, "simulate", scene, "--out", out)
    check(r.returncode == 0, f"{tag}: simulate", r)
    if r.returncode != 0:
        return
    data, rows = read_csv(out), table(r.stdout)
    check(set(rows) == {"shoulder", "wrist:twist", "wrist:swing1", "wrist:swing2"},
          f"{tag}: a row per drive: {sorted(rows)}", r)
    t = data["t"]
    for joint, cells in rows.items():
        q = data[f"q:{joint}"]
        errors = [wrist_target(joint, t[k]) - q[k] for k in range(1, len(t))]
        want = [errors[-1], math.sqrt(sum(e * e for e in errors) / len(errors)),
                max(abs(e) for e in errors)]
        for name, got, expected in zip(("final", "rms", "max"), cells[0:3], want):
            check(abs(float(got) - expected) <= 1e-3 * abs(expected) + 1e-12,
                  f"{tag}: {joint} {name} error {got} = target - CSV {expected:.4e}", r)
    check("rad" in r.stdout and "N m" in r.stdout, f"{tag}: units in the header", r)
    # Row k's target columns: the command of the step from row k (the scene's at (k + 1) dt).
    dt = t[1] - t[0]
    for joint in rows:
        got = data[f"target:{joint}"]
        check(all(abs(got[k] - wrist_target(joint, (k + 1) * dt)) < 1e-12 for k in range(len(t))),
              f"{tag}: target:{joint} is the scene's target of each row's step")


def fit_round_trip(cli, source, out_dir):
    urdf = os.path.join(source, "examples", "arm7.urdf")
    head = (f"model: {urdf}\ndt: 0.004166666666666667\nsteps: 240\n"
            "solver: {type: tgs, position_iterations: 4, velocity_iterations: 1}\n")
    drives = "drives:\n" + "".join(
        f"  joint{j}: {{type: force, stiffness: {s}, damping: {d}, target: {{sine: "
        f"{{amplitude: 0.3, frequency: {0.7 + 0.3 * j}}}}}}}\n"
        for j, s, d in [(1, 400, 10), (2, 900, 25), (3, 400, 10), (4, 600, 15), (5, 400, 10),
                        (6, 400, 10), (7, 400, 10)])
    truth = os.path.join(out_dir, "faces_truth.yaml")
    with open(truth, "w") as f:
        f.write(head + drives)
    log = os.path.join(out_dir, "faces_log.csv")
    r = run(cli, "simulate", truth, "--out", log)
    check(r.returncode == 0, "fit round trip: simulate the log", r)
    guess = drives.replace("stiffness: 900, damping: 25", "stiffness: 500, damping: 10").replace(
        "stiffness: 600, damping: 15", "stiffness: 500, damping: 10")
    fit_scene = os.path.join(out_dir, "faces_fit.yaml")
    with open(fit_scene, "w") as f:
        f.write(head + guess + "fit:\n  parameters:\n"
                "    - {quantity: stiffness, joints: [joint2, joint4], bounds: [50, 5000]}\n"
                "    - {quantity: damping, joints: [joint2, joint4], bounds: [0.5, 100]}\n")
    r = run(cli, "fit", fit_scene, "--data", log, "--threads", "1",
            "--out", os.path.join(out_dir, "faces_fit_out"))
    check(r.returncode == 0, "fit reads simulate's log", r)
    # The fitted values: one row per (quantity, joint) of the table.
    found = {}
    for line in r.stdout.splitlines():
        words = line.split()
        if len(words) >= 4 and words[0] in ("stiffness", "damping") and words[1].startswith("joint"):
            found[(words[0], words[1])] = float(words[3])
    for key, want in {("stiffness", "joint2"): 900, ("damping", "joint2"): 25,
                      ("stiffness", "joint4"): 600, ("damping", "joint4"): 15}.items():
        got = found.get(key)
        check(got is not None and abs(got - want) <= 1e-4 * want,
              f"fit recovers {key} = {want} within 1e-4 (got {got})", r)


def shares(cli, source, out_dir):
    urdf = os.path.join(source, "examples", "slider.urdf")
    base = (f"model: {urdf}\ngravity: [0, 0, 0]\ndt: 0.016666666666666666\nsteps: 60\n"
            "solver: {type: pgs, position_iterations: 4, velocity_iterations: 1}\n"
            "drives: {slide: {type: force, stiffness: 0, damping: 1000000, max_force: 4, "
            "target_velocity: 1}}\n")
    for tag, extra, want in [("saturation", "", ("61.7 %", "0.0 %")),
                             ("velocity limit", "joints: {slide: {max_velocity: 0.5}}\n",
                              ("100.0 %", "70.0 %"))]:
        scene = os.path.join(out_dir, f"faces_{tag.replace(' ', '_')}.yaml")
        with open(scene, "w") as f:
            f.write(base + extra)
        r = run(cli, "simulate", scene)
        row = table(r.stdout).get("slide", [])
        got = tuple(row[4:6]) if len(row) == 7 else None
        check(r.returncode == 0 and got == want,
              f"{tag}: at max_force / at the velocity limit {got}, closed form {want}", r)


def implicit_actuator(cli, source, out_dir):
    urdf = os.path.join(source, "examples", "slider.urdf")
    # A target near enough that the URDF's 10 m/s velocity limit never acts.
    m, h, kp, kd, target = 2.5, 1.0 / 60.0, 100 * 2.5 * 3600.0, 30.0, 0.02
    scene = os.path.join(out_dir, "faces_implicit_actuator.yaml")
    with open(scene, "w") as f:
        f.write(f"model: {urdf}\ngravity: [0, 0, 0]\ndt: {h!r}\nsteps: 30\n"
                f"drives: {{slide: {{type: none, target_position: {target}, actuator: "
                f"{{type: ideal_pd, stiffness: {kp!r}, damping: {kd}, integration: implicit}}}}}}\n")
    out = os.path.join(out_dir, "faces_implicit_actuator.csv")
    r = run(cli, "simulate", scene, "--out", out)
    check(r.returncode == 0 and re.search(r"^\s+slide\s+actuator\(implicit\)\s", r.stdout, re.M),
          "the summary names the implicit actuator", r)
    if r.returncode != 0:
        return
    data = read_csv(out)
    x = v = 0.0
    for k in range(1, 31):
        v0 = v
        v = (m * v + h * kp * (target - x)) / (m + h * kd + h * h * kp)
        x += h * v
        check(abs(data["q:slide"][k] - x) <= 1e-12 and
              abs(data["f:slide"][k] - m * (v - v0) / h) <= 1e-9 * max(1.0, abs(m * (v - v0) / h)),
              f"implicit actuator step {k}: q {data['q:slide'][k]} vs {x}, "
              f"f {data['f:slide'][k]} vs {m * (v - v0) / h}")


def joint_spring(cli, source, out_dir):
    """The summary names the spring with its fields and reports the last step's force, which is
    the spring law at the step's end state, -k (q - x_s) - c qd (docs/math/joint_constraints.md,
    JS1; PGS without velocity iterations, the spring the slider's only row), from the CSV."""
    scene = os.path.join(out_dir, "faces_spring.yaml")
    with open(scene, "w") as f:
        f.write("model: " + os.path.join(source, "examples", "slider.urdf") + "\nsteps: 40\n"
                "solver: {type: pgs, position_iterations: 4, velocity_iterations: 0}\n"
                "joints: {slide: {joint_spring: {stiffness: 300, damping: 2, reference: 0.2}}}\n")
    out = os.path.join(out_dir, "faces_spring.csv")
    r = run(cli, "simulate", scene, "--out", out)
    m = re.search(r"^\s+slide: stiffness 300 damping 2 reference 0.2, last step's force (\S+)$",
                  r.stdout, re.M)
    check(r.returncode == 0 and m is not None, "spring: the summary names it", r)
    if m is None:
        return
    columns = read_csv(out)
    expected = -300 * (columns["q:slide"][-1] - 0.2) - 2 * columns["qd:slide"][-1]
    check(abs(float(m.group(1)) - expected) <= 1e-5 * max(1.0, abs(expected)),
          f"spring: last force {m.group(1)} against -k (q - x_s) - c qd = {expected}", r)


def convergence(cli, source):
    scene = os.path.join(source, "examples", "arm7_pgs.yaml")
    r = run(cli, "simulate", scene)
    check(r.returncode == 0 and "not converged" in r.stderr and "joint1" in r.stderr,
          "PGS 4/1 on the arm warns that joint1's drive has not converged", r)
    r = run(cli, "simulate", scene, "--position-iterations", "64")
    check(r.returncode == 0 and "not converged" not in r.stderr, "64 iterations converge", r)


def main():
    cli, source, out_dir = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
    os.makedirs(out_dir, exist_ok=True)
    wrist = os.path.join(source, "examples", "spherical_wrist.yaml")
    summary_is_the_csv(cli, wrist, os.path.join(out_dir, "faces_wrist.csv"), "spherical wrist")
    floating = os.path.join(out_dir, "faces_floating.yaml")
    with open(wrist) as f:
        text = f.read()
    with open(floating, "w") as f:
        f.write(text.replace("model: spherical_wrist.urdf",
                             "model: " + os.path.join(source, "tests", "data",
                                                      "spherical_floating.urdf") +
                             "\nfixed_base: false"))
    summary_is_the_csv(cli, floating, os.path.join(out_dir, "faces_floating.csv"), "floating")
    with open(os.path.join(out_dir, "faces_floating.csv")) as f:
        header = f.readline()
    check(header.startswith("step,t,q:"), "floating: the root's columns first")
    fit_round_trip(cli, source, out_dir)
    shares(cli, source, out_dir)
    convergence(cli, source)
    implicit_actuator(cli, source, out_dir)
    joint_spring(cli, source, out_dir)
    r = run(cli, "--version")
    check(r.returncode == 0 and r.stdout.startswith("featherdrive "), "--version", r)
    r = run(cli, "simulate", "--help")
    check("--steps INT" in r.stdout and "--position-iterations INT" in r.stdout,
          "integer options show INT in --help", r)
    if failures:
        print("FAIL:\n" + "\n".join(failures))
        sys.exit(1)
    print("ok: summary = CSV on a ball joint and a floating base, fit reads simulate's log, "
          "shares at bounds, convergence warning, an implicit actuator, a joint spring")


if __name__ == "__main__":
    main()
