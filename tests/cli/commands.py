#!/usr/bin/python3
"""The command line itself: info, option overrides, exit codes 0 / 1 / 2, warnings.

usage: commands.py FEATHERDRIVE SOURCE_DIR OUT_DIR
"""
import csv
import os
import subprocess
import sys

failures = []



def run(*args):
    return subprocess.run(list(args), capture_output=True, text=True, timeout=120)


def check(condition, what, result=None):
    if not condition:
        detail = f"\n  rc={result.returncode} stdout={result.stdout!r} stderr={result.stderr!r}" if result else ""
        failures.append(what + detail)


def one_line_error(result, code, text):
    check(result.returncode == code, f"exit code {code} for {text!r}", result)
    check(len(result.stderr.strip().splitlines()) == 1, f"one stderr line for {text!r}", result)
    check(text in result.stderr, f"stderr holds {text!r}", result)


def contact(cli, source, out_dir):
    """Collision geometry and the ground (issue 34): info lists a robot's shapes, what contacts
    cannot use yet and an MJCF floor; simulate prints the ground and the shapes and its CSV has
    contact:<link>:fx,fy,fz columns; a checkpoint keeps the ground and its model's shapes."""
    chain = os.path.join(source, "examples", "chain3.urdf")
    collisions = os.path.join(source, "tests", "data", "collisions.urdf")

    r = run(cli, "info", collisions)
    check(r.returncode == 0, "info collisions.urdf", r)
    for text in ("collision shapes (6, poses in the link frame):",
                 "  base: box 'body' (half extents [0.2, 0.1, 0.05]) at [0, 0, 0.05] m, sphere (r 0.05)",
                 "cylinder 'wheel' (r 0.1, half length 0.025) at [0, 0, 0] m",
                 "  arm: box 'arm_box'",
                 "not usable by contacts yet: " + "link 'arm': mesh collision 'package://collisions/arm.ply' (meshes are read from STL, OBJ, MSH, DAE)"):
        check(text in r.stdout, f"info collisions.urdf shows {text!r}", r)
    r = run(cli, "info", "/usr/share/mujoco/model/humanoid/humanoid.xml")
    check("ground (the file's floor): height 0 m, normal [0, 0, 1], friction 1 / 1, restitution 0"
          in r.stdout, "info humanoid shows its floor", r)

    shapes = ("drive_defaults: {type: force, stiffness: 100, damping: 10}\nshapes:\n"
              "  - {link: link3, type: sphere, radius: 0.05, name: tip}\n"
              "  - {link: link1, type: box, half_extents: [0.1, 0.1, 0.1]}\n")

    def scene_file(name, text):
        path = os.path.join(out_dir, name)
        with open(path, "w") as f:
            f.write(f"model: {chain}\ndt: 0.01\n" + text)
        return path

    scene = scene_file("contact_scene.yaml", "steps: 3\nground: {height: -2, static_friction: 0.8}\n"
                       "contact: {contact_offset: 0.03}\n" + shapes)
    out_csv = os.path.join(out_dir, "contact_scene.csv")
    state = os.path.join(out_dir, "contact_scene.ckpt")
    r = run(cli, "simulate", scene, "--out", out_csv, "--save-state", state)
    check(r.returncode == 0, "simulate a scene with a ground", r)
    check("  ground: height -2 m, normal [0, 0, 1], friction 0.8 / 0.5, restitution 0; contact "
          "offset 0.03 m, rest offset 0 m, bounce threshold 2 m/s" in r.stdout,
          "simulate prints the ground", r)
    check("  collision shapes (2):\n    link1: box (half extents [0.1, 0.1, 0.1]) at [0, 0, 0] m\n"
          "    link3: sphere 'tip' (r 0.05) at [0, 0, 0] m\n" in r.stdout,
          "simulate prints the shapes per link", r)
    if os.path.exists(out_csv):
        with open(out_csv) as f:
            rows = list(csv.reader(f))
        header = rows[0]
        wanted = [f"contact:{link}:{axis}" for link in ("link1", "link3") for axis in ("fx", "fy", "fz")]
        check(header[-6:] == wanted, f"the CSV ends with {wanted}, not {header[-6:]}")
        check(len(rows) == 5 and all(len(row) == len(header) for row in rows), "5 whole rows")
        check(rows[1][-6:] == ["0"] * 6, "the initial row's contact forces are 0")
    # Self-collision without a ground: the CSV has the contact columns and simulate says so.
    stack = os.path.join(source, "tests", "data", "stack.urdf")  # a ball above its base's sphere
    selfish = os.path.join(out_dir, "self_collision.yaml")
    with open(selfish, "w") as f:
        f.write(f"model: {stack}\ndt: 0.01\nsteps: 300\nsolver: {{position_iterations: 50}}\n"
                "initial: {q: {drop: 0.16}}\ncontact: {self_collision: true}\n")
    self_csv = os.path.join(out_dir, "self_collision.csv")
    r = run(cli, "simulate", selfish, "--out", self_csv)
    check(r.returncode == 0 and "  self-collision: on" in r.stdout, "simulate with self-collision", r)
    if os.path.exists(self_csv):
        with open(self_csv) as f:
            rows = list(csv.reader(f))
        fz = rows[0].index("contact:ball:fz")
        # The ball (2 kg) rests on the base's sphere: the base holds it up with m g.
        check(abs(float(rows[-1][fz]) - 2 * 9.81) < 1e-6, f"the ball's contact force {rows[-1][fz]}")
    # The checkpoint keeps the ground: resuming in a scene without one gives the file's.
    plain = scene_file("contact_plain.yaml", "steps: 1\n" + shapes)
    r = run(cli, "simulate", plain, "--load-state", state)
    check(r.returncode == 0 and "  ground: height -2 m" in r.stdout,
          "a resumed run has the checkpoint's ground", r)
    # A scene without the shapes is another model: its checkpoint is refused.
    bare = scene_file("contact_bare.yaml", "steps: 1\n")
    r = run(cli, "simulate", bare, "--load-state", state)
    check(r.returncode == 2 and "different model" in r.stderr,
          "a checkpoint of the model with shapes is refused without them", r)


def main():
    cli, source, out_dir = sys.argv[1:4]
    os.makedirs(out_dir, exist_ok=True)
    ex = lambda name: os.path.join(source, "examples", name)  # noqa: E731
    data = lambda name: os.path.join(source, "tests", "data", name)  # noqa: E731

    r = run(cli, "info", ex("arm7.urdf"))
    check(r.returncode == 0 and r.stderr == "", "info arm7 succeeds quietly", r)
    for text in ("robot 'arm7'", "7 dofs", "fixed base", "total mass 19.6 kg", "joint7: revolute",
                 "limits [-2.8, 2.8] rad", "effort 150 Nm", "merged through fixed joints: hand, tcp"):
        check(text in r.stdout, f"info arm7 shows {text!r}", r)
    r = run(cli, "info", ex("chain3.urdf"), "--floating")
    check(r.returncode == 0 and "floating base" in r.stdout and "9 dofs" in r.stdout, "info --floating", r)
    r = run(cli, "info", data("branches.urdf"))
    check(r.returncode == 0, "info branches", r)
    check("mimic: left = -0.5 * right1 + 0.01 (a mimic joint in scenes)" in r.stdout,
          "info shows the mimic joint", r)
    check("dofs in the file's order: right1 left right2" in r.stdout, "info lists dofs in URDF order", r)

    # check: the verdict is the last line, exit 0 for both verdicts, 2 for bad input.
    r = run(cli, "check", ex("slider.yaml"))
    check(r.returncode == 0 and r.stdout.splitlines()[-1] == "verdict: stable",
          "check slider: verdict stable", r)
    check(any(line.split()[:2] == ["slide", "drive"] for line in r.stdout.splitlines()),
          "check slider: the table has the drive", r)
    unstable = os.path.join(out_dir, "check_unstable.yaml")
    with open(unstable, "w") as f:  # an undamped explicit PD at kp dt^2/m = 200 (stable to 4)
        f.write(f"model: {ex('slider.urdf')}\ndt: 0.01\nsteps: 10\ndrives:\n"
                "  slide: {type: none, target_position: 0.1, "
                "actuator: {type: ideal_pd, stiffness: 5000000}}\n")
    r = run(cli, "check", unstable)
    last = r.stdout.splitlines()[-1] if r.stdout else ""
    check(r.returncode == 0 and last.startswith("verdict: unstable: slide (explicit_pd"),
          "check: an explicit PD past kp dt^2/m = 4 is unstable", r)
    # The fixes from the threshold 4: 200 / n^2 <= 4 from n = 8; armature kp dt^2 / 4 - m.
    check("substeps 8 (dt 0.00125" in r.stdout and "armature +122.5" in r.stdout
          and "damping: none" in r.stdout, "check: the fixes of the slider", r)
    r = run(cli, "check", ex("slider.yaml"), "--trial-steps", "0")
    check(r.returncode == 0 and "trial run" not in r.stdout
          and r.stdout.splitlines()[-1] == "verdict: stable", "check --trial-steps 0: no trial", r)
    r = run(cli, "check", ex("slider.yaml"), "--trial-steps", "2000")
    check(r.returncode == 0 and "trial run of 2000 steps" in r.stdout, "check --trial-steps 2000", r)
    one_line_error(run(cli, "check", ex("slider.yaml"), "--trial-steps", "-1"), 2, "--trial-steps")
    one_line_error(run(cli, "check", ex("slider.yaml"), "--steps", "50"), 2,
                   "--steps = 50: check runs no scene steps")
    one_line_error(run(cli, "check", os.path.join(out_dir, "no_such_scene.yaml")), 2,
                   "no_such_scene.yaml")
    one_line_error(run(cli, "check", data("malformed/applied_force_nan.yaml")), 2,
                   "applied_force.slide")
    one_line_error(run(cli, "check"), 2, "scene is required")

    # Overrides: steps, solver, iterations.
    out = os.path.join(out_dir, "chain3_override.csv")
    r = run(cli, "simulate", ex("chain3.yaml"), "--steps", "7", "--solver", "pgs",
            "--position-iterations", "2", "--velocity-iterations", "0", "--out", out)
    check(r.returncode == 0, "simulate with overrides", r)
    check("pgs" in r.stdout and "2 position / 0 velocity iterations" in r.stdout and "7 steps" in r.stdout,
          "the summary shows the overrides", r)
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    check(len(rows) == 1 + 8, f"--steps 7 gives 8 rows, got {len(rows) - 1}")
    check(rows[1][2:11] == ["0"] * 9, f"row 0 is the initial state at rest with f = 0: {rows[1]}")
    r = run(cli, "simulate", ex("chain3.yaml"), "--steps", "0")
    check(r.returncode == 0, "--steps 0 runs", r)

    # --substeps: the scene's control.substeps; the sine target changes every 4 steps only.
    def rows_of(path):
        with open(path, newline="") as f:
            return list(csv.reader(f))
    by_option, by_key, plain = (os.path.join(out_dir, f"slider_{n}.csv")
                                for n in ("opt", "key", "1"))
    r = run(cli, "simulate", ex("slider.yaml"), "--steps", "8", "--substeps", "4",
            "--out", by_option)
    check(r.returncode == 0 and "control step: 4 physics steps, targets hold" in r.stdout,
          "--substeps 4 runs and the summary says so", r)
    keyed = os.path.join(out_dir, "slider_control.yaml")
    with open(ex("slider.yaml")) as f, open(keyed, "w") as g:
        g.write(f.read().replace("model: slider.urdf", f"model: {ex('slider.urdf')}")
                + "control: {substeps: 4}\n")
    r = run(cli, "simulate", keyed, "--steps", "8", "--out", by_key)
    check(r.returncode == 0, "a scene with control: {substeps: 4} runs", r)
    r = run(cli, "simulate", ex("slider.yaml"), "--steps", "8", "--out", plain)
    opt_rows, key_rows, plain_rows = rows_of(by_option), rows_of(by_key), rows_of(plain)
    check(len(opt_rows) == 1 + 9, f"--substeps keeps one row per physics step: {len(opt_rows) - 1}")
    check(opt_rows == key_rows, "--substeps 4 gives the CSV of control: {substeps: 4}")
    # Row 0's state is the same; its target column (the command of step 0) is that of t = 4 dt.
    state = lambda rows: [r[:5] for r in rows]  # noqa: E731 (step, t, q, qd, f)
    check(state(opt_rows[:2]) == state(plain_rows[:2]) and opt_rows[2:] != plain_rows[2:],
          "--substeps 4 holds the target of t = 4 dt from step 0 (1 step per target differs)")
    check(float(opt_rows[1][5]) == float(plain_rows[4][5]),
          "--substeps 4: row 0's target is the plain run's target of step 3 (t = 4 dt)")
    one_line_error(run(cli, "simulate", ex("slider.yaml"), "--substeps", "0"), 2,
                   "--substeps = 0: must be between 1 and 1000000")

    # Bad command lines and inputs: exit 2, one line.
    one_line_error(run(cli, "simulate", ex("chain3.yaml"), "--solver", "sor"), 2, "--solver")
    one_line_error(run(cli, "simulate", ex("chain3.yaml"), "--position-iterations", "0"), 2,
                   "--position-iterations")
    one_line_error(run(cli, "simulate", ex("chain3.yaml"), "--steps", "-3"), 2, "--steps")
    one_line_error(run(cli, "simulate", ex("chain3.yaml"), "--steps", "many"), 2, "--steps")
    one_line_error(run(cli, "simulate", ex("missing.yaml")), 2, "missing.yaml: cannot open the file")
    one_line_error(run(cli, "info", ex("missing.urdf")), 2, "missing.urdf: cannot open the file")
    one_line_error(run(cli, "fly"), 2, "fly")
    one_line_error(run(cli), 2, "subcommand")
    one_line_error(run(cli, "simulate"), 2, "scene")
    r = run(cli, "--help")
    check(r.returncode == 0 and "simulate" in r.stdout, "--help", r)

    # A simulation that blows up: exit 1 with the DivergenceError's message.
    diverge = os.path.join(out_dir, "diverge.yaml")
    with open(diverge, "w") as f:
        f.write(f"model: {ex('slider.urdf')}\ngravity: [0, 0, -1e307]\ndt: 1\nsteps: 100\n"
                "joints: {slide: {lower: -.inf, upper: .inf, max_velocity: .inf}}\n")
    one_line_error(run(cli, "simulate", diverge), 1, "simulation diverged")

    # The step guard (docs/math/step_guard.md): the summary counts the redone steps, the CSV's
    # guard_substeps column has the n of each, and a bad bound is one line, exit 2.
    guarded = os.path.join(out_dir, "guarded.yaml")
    base = (f"model: {ex('slider.urdf')}\ndt: 0.03333333333333333\nsteps: 20\n"
            "drives: {slide: {type: force, stiffness: 900, damping: 10, target_position: 0.5}}\n")
    with open(guarded, "w") as f:
        f.write(base + "guard: {max_joint_step: 0.06}\n")
    trajectory = os.path.join(out_dir, "guarded.csv")
    r = run(cli, "simulate", guarded, "--out", trajectory)
    check(r.returncode == 0, "a guarded simulation succeeds", r)
    with open(trajectory) as f:
        rows = list(csv.DictReader(f))
    substeps = [int(row["guard_substeps"]) for row in rows]
    redone = sum(1 for n in substeps if n > 1)
    check(substeps[0] == 1 and redone > 0 and all(n in (1, 2, 4, 8, 16, 32, 64) for n in substeps),
          f"guard_substeps column: {substeps}", r)
    check(f"step guard (max_joint_step 0.06, max_substeps 64, energy_tolerance 0.02, "
          f"dissipation_share 0.15): {redone} "
          f"steps redone, largest "
          f"{max(substeps)} sub-steps, 0 exhausted" in r.stdout, "the guard's summary line", r)
    r = run(cli, "simulate", ex("slider.yaml"), "--out", os.path.join(out_dir, "plain.csv"))
    with open(os.path.join(out_dir, "plain.csv")) as f:
        check("guard_substeps" not in f.readline(), "no guard column without the guard", r)
    with open(guarded, "w") as f:
        f.write(base + "guard: {max_substeps: 0}\n")
    one_line_error(run(cli, "simulate", guarded), 2, "guard.max_substeps = 0: must be >= 2")

    # An output that cannot be written: exit 1.
    r = run(cli, "simulate", ex("chain3.yaml"), "--out", "/proc/featherdrive/x.csv")
    check(r.returncode == 1, "an unwritable --out exits 1", r)
    contact(cli, source, out_dir)

    if failures:
        for f in failures:
            print("FAIL:", f)
        sys.exit(1)
    print("ok")


if __name__ == "__main__":
    main()
