#!/usr/bin/python3
"""`featherdrive compare-physx`: the arm against PhysX (mode `physx`, needs the harness installed:
the ctest fixture `physx`), and the one-line messages without node or without the PhysX package
and for bad input (mode `messages`, needs neither).

usage: compare_physx.py FEATHERDRIVE SOURCE_DIR OUT_DIR physx|messages
"""
import os
import re
import subprocess
import sys

failures = []
JOINTS = [f"joint{i}" for i in range(1, 8)]


def run(*args, env=None):
    return subprocess.run(list(args), capture_output=True, text=True, timeout=300, env=env)


def check(condition, what, result=None):
    if not condition:
        detail = f"\n  rc={result.returncode} stdout={result.stdout!r} stderr={result.stderr!r}" if result else ""
        failures.append(what + detail)


def one_line_error(result, code, texts, what):
    check(result.returncode == code, f"{what}: exit code {code}", result)
    check(len(result.stderr.strip().splitlines()) == 1, f"{what}: one line on stderr", result)
    check(result.stdout == "", f"{what}: nothing on stdout", result)
    for text in texts:
        check(text in result.stderr, f"{what}: stderr holds {text!r}", result)


def environment(**changes):
    env = dict(os.environ)
    env.pop("FEATHERDRIVE_PHYSX_DIR", None)
    env.update(changes)
    return env


def physx(cli, source, out_dir):
    png = os.path.join(out_dir, "arm7_physx_diff.png")
    if os.path.exists(png):
        os.remove(png)
    scene = os.path.join(source, "examples", "arm7_pgs.yaml")
    r = run(cli, "compare-physx", scene, "--plot", png, env=environment())
    check(r.returncode == 0, "compare-physx arm7_pgs succeeds", r)
    out = r.stdout
    check("7 dofs" in out and "360 steps" in out and "solver pgs 4/1" in out, "the run is described", r)
    check("joint friction off on both sides" in out, "the friction PhysX cannot take is named", r)
    header = re.search(r"^\s+joint\s+q\s+step\s+relative\s+qd\s+step\s+relative\s+force\s+step\s+relative\s*$",
                       out, re.M)
    check(header is not None, "the table's columns: joint, then q / qd / force with step and relative", r)
    number = r"([-+0-9.e]+)"
    rows = {}
    for joint in JOINTS:
        m = re.search(rf"^\s+{joint}\s+" + r"\s+".join([number] * 9) + r"\s*$", out, re.M)
        check(m is not None, f"a row for {joint}", r)
        if m:
            rows[joint] = [float(x) for x in m.groups()]
    scale = re.search(r"^\s+scale\s+" + r"\s+".join([number] * 3) + r"\s*$", out, re.M)
    check(scale is not None, "the scale row", r)
    if scale and len(rows) == len(JOINTS):
        sq, sqd, sf = (float(x) for x in scale.groups())
        check(sq > 0.5 and sqd > 0.5 and sf > 1.0, f"a scale of a moving arm: {sq} {sqd} {sf}")
        for joint, v in rows.items():
            for i, (name, s) in enumerate((("q", sq), ("qd", sqd), ("force", sf))):
                diff, step, rel = v[3 * i:3 * i + 3]
                # The parity tests establish 1e-4 of the run's scale for free runs independently.
                check(diff <= 1e-4 * s, f"{joint} {name}: difference {diff} within 1e-4 of the scale {s}")
                check(abs(rel - diff / s) <= 0.06 * rel + 1e-12, f"{joint} {name}: relative {rel} = {diff} / {s}")
                check(0 <= step <= 360 and step == int(step), f"{joint} {name}: step {step} in 0..360")
    overall = re.search(r"largest relative difference: q " + number + ", qd " + number + ", force " + number, out)
    check(overall is not None and max(float(x) for x in overall.groups()) < 1e-4,
          "the largest relative difference is below 1e-4", r)
    check(f"plot: {png}" in out, "the plot is reported", r)
    with open(png, "rb") as f:
        check(f.read(8) == b"\x89PNG\r\n\x1a\n", "the plot is a PNG")

    # A URDF whose fixed root has no <inertial> (PhysX gets a stand-in mass for it); the arm under
    # compat physx with PhysX's defaults on both sides.
    # MuJoCo's humanoid: its bodies with several joints give massless links, to which PhysX gets
    # 1e-6 of their body's mass (docs/physx_parity.md); the free-run tolerance holds.
    for name in ("slider.yaml", "pendulum.yaml", "arm7_physx.yaml", "humanoid_hold.yaml"):
        r = run(cli, "compare-physx", os.path.join(source, "examples", name), env=environment())
        m = re.search(r"largest relative difference: q " + number + ", qd " + number + ", force " + number, r.stdout)
        check(r.returncode == 0 and m is not None and max(float(x) for x in m.groups()) < 1e-4,
              f"compare-physx {name} agrees within 1e-4", r)

    # Joint names with a comma, quotes, a backslash and a space reach the real harness (JSON
    # escaped, CSV header quoted) and the pendulum agrees with PhysX as the plain one does.
    with open(os.path.join(source, "examples", "pendulum.urdf")) as f:
        urdf = f.read()
    odd = 'hi, "nge" \\x'
    with open(os.path.join(out_dir, "odd_names.urdf"), "w") as f:
        f.write(urdf.replace('name="hinge"', 'name="hi, &quot;nge&quot; \\x"'))
    odd_scene = os.path.join(out_dir, "odd_names.yaml")
    with open(odd_scene, "w") as f:
        f.write("model: odd_names.urdf\ndt: 0.01\nsteps: 50\n"
                "initial: {q: {'" + odd.replace("'", "''") + "': 0.5}}\n")
    r = run(cli, "compare-physx", odd_scene, env=environment())
    m = re.search(r"largest relative difference: q " + number + ", qd " + number + ", force " + number, r.stdout)
    check(r.returncode == 0 and m is not None and max(float(x) for x in m.groups()) < 1e-4
          and re.search(r"^\s+" + re.escape(odd) + r"\s", r.stdout, re.M) is not None,
          "compare-physx with a joint named with a comma, quotes and a backslash", r)

    # Overrides reach both sides: TGS, 2 steps.
    r = run(cli, "compare-physx", scene, "--steps", "2", "--solver", "tgs", "--position-iterations", "8",
            "--velocity-iterations", "2", env=environment())
    check(r.returncode == 0 and "2 steps" in r.stdout and "solver tgs 8/2" in r.stdout,
          "compare-physx with overrides", r)


def messages(cli, source, out_dir):
    scene = os.path.join(source, "examples", "arm7_pgs.yaml")
    # No node on PATH (an empty folder is the whole PATH).
    empty = os.path.join(out_dir, "empty_path")
    os.makedirs(empty, exist_ok=True)
    r = run(cli, "compare-physx", scene, env=environment(PATH=empty))
    one_line_error(r, 1, ["node", "not on PATH", "apt-get install -y nodejs npm", "make physx"], "without node")
    # The package missing: FEATHERDRIVE_PHYSX_DIR is an empty folder.
    empty_dir = os.path.join(out_dir, "empty_physx")
    os.makedirs(empty_dir, exist_ok=True)
    r = run(cli, "compare-physx", scene, env=environment(FEATHERDRIVE_PHYSX_DIR=empty_dir))
    one_line_error(r, 1, [f"FEATHERDRIVE_PHYSX_DIR = {empty_dir}: no harness.js",
                          f"tests/physx/install.sh {empty_dir}", "apt-get install -y nodejs npm"],
                   "without the package")
    # Bad input is exit 2 before any PhysX is looked for.
    one_line_error(run(cli, "compare-physx", scene, "--position-iterations", "300", env=environment(PATH=empty)),
                   2, ["--position-iterations = 300: PhysX allows 1 to 255"], "too many iterations for PhysX")
    one_line_error(run(cli, "compare-physx", os.path.join(source, "examples", "missing.yaml")), 2,
                   ["missing.yaml: cannot open the file"], "a missing scene")
    one_line_error(run(cli, "compare-physx", scene, "--solver", "sor"), 2, ["--solver"], "a bad solver")
    one_line_error(run(cli, "compare-physx"), 2, ["scene"], "no scene")
    # What PhysX cannot represent names the scene and the joint.
    envelope = os.path.join(out_dir, "envelope.yaml")
    with open(envelope, "w") as f:
        f.write(f"model: {os.path.join(source, 'examples', 'slider.urdf')}\nsteps: 3\n"
                "drives: {slide: {type: force, stiffness: 10, damping: 1, envelope: {max_effort: 5}}}\n")
    one_line_error(run(cli, "compare-physx", envelope, env=environment(PATH=empty)), 2,
                   [f"{envelope}: physx export: joint 'slide' has an actuator envelope"], "an envelope")
    # An actuator (either integration): PhysX has no actuator model.
    for integration in ("explicit", "implicit"):
        actuated = os.path.join(out_dir, f"actuated_{integration}.yaml")
        with open(actuated, "w") as f:
            f.write(f"model: {os.path.join(source, 'examples', 'slider.urdf')}\nsteps: 3\n"
                    "drives: {slide: {type: none, actuator: {type: dc_motor, stiffness: 10, "
                    f"saturation_effort: 5, velocity_limit: 1, integration: {integration}}}}}}}\n")
        one_line_error(run(cli, "compare-physx", actuated, env=environment(PATH=empty)), 2,
                       [f"{actuated}: physx export: joint 'slide' has an {integration} dc_motor "
                        "actuator, which the harness cannot set"], f"an {integration} actuator")
    # The step guard: PhysX would step unguarded, so the comparison is refused.
    guarded = os.path.join(out_dir, "guarded.yaml")
    with open(guarded, "w") as f:
        f.write(f"model: {os.path.join(source, 'examples', 'slider.urdf')}\nsteps: 3\n"
                "drives: {slide: {type: force, stiffness: 10, damping: 1}}\nguard: {}\n")
    one_line_error(run(cli, "compare-physx", guarded, env=environment(PATH=empty)), 2,
                   [f"{guarded}: physx export: the step guard (guard:) has no PhysX counterpart"],
                   "a guarded scene")
    # A shape the harness cannot build (PhysX's ellipsoids and cylinders are cooked meshes) with
    # the ground on (without it the shape touches nothing and is left out).
    egg = os.path.join(out_dir, "ellipsoid.yaml")
    with open(egg, "w") as f:
        f.write(f"model: {os.path.join(source, 'examples', 'chain3.urdf')}\nsteps: 3\nground: {{}}\n"
                "shapes:\n  - {link: link3, type: ellipsoid, radii: [0.1, 0.2, 0.3], name: egg}\n")
    one_line_error(run(cli, "compare-physx", egg, env=environment(PATH=empty)), 2,
                   [f"{egg}: physx export: shape 'egg' (ellipsoid) of link 'link3': the PhysX "
                    "harness builds spheres, capsules and boxes only (leave the ground off"],
                   "an ellipsoid")
    # Self-collision: the harness builds none, so the comparison is refused.
    selfish = os.path.join(out_dir, "self_collision.yaml")
    with open(selfish, "w") as f:
        f.write(f"model: {os.path.join(source, 'examples', 'chain3.urdf')}\nsteps: 3\n"
                "contact: {self_collision: true}\n")
    one_line_error(run(cli, "compare-physx", selfish, env=environment(PATH=empty)), 2,
                   [f"{selfish}: physx export: contact.self_collision: the harness builds no "
                    "self-collision"], "self-collision")


def main():
    cli, source, out_dir, mode = sys.argv[1:5]
    source = os.path.abspath(source)
    os.makedirs(out_dir, exist_ok=True)
    {"physx": physx, "messages": messages}[mode](cli, source, out_dir)
    if failures:
        print("\n".join(failures))
        sys.exit(1)
    print(f"compare-physx {mode}: all checks passed")


if __name__ == "__main__":
    main()
