#!/usr/bin/python3
"""`featherdrive compare-mujoco` and `featherdrive translate --to mujoco` on the shipped slider
scene: the tables, the plot, the MJCF, and one-line messages for bad input.

usage: compare_mujoco.py FEATHERDRIVE SOURCE_DIR OUT_DIR
"""
import os
import re
import subprocess
import sys

failures = []
NUMBER = r"([-+0-9.e]+|inf|nan)"


def run(*args):
    return subprocess.run(list(args), capture_output=True, text=True, timeout=300)


def check(condition, what, result=None):
    if not condition:
        detail = (f"\n  rc={result.returncode} stdout={result.stdout!r} stderr={result.stderr!r}"
                  if result else "")
        failures.append(what + detail)


def one_line_error(result, texts, what):
    check(result.returncode == 2, f"{what}: exit code 2", result)
    check(len(result.stderr.strip().splitlines()) == 1, f"{what}: one line on stderr", result)
    for text in texts:
        check(text in result.stderr, f"{what}: stderr holds {text!r}", result)


def tables(out):
    """The rows of each table, in order: {joint: [q, step, rel, qd, step, rel, f, step, rel]}."""
    found = []
    for block in out.split("largest |featherdrive - MuJoCo")[1:]:
        rows = {}
        for m in re.finditer(r"^\s+(\S+)\s+" + r"\s+".join([NUMBER] * 9) + r"\s*$", block, re.M):
            rows[m.group(1)] = [float(x) for x in m.groups()[1:]]
        found.append(rows)
    return found


def read_csv(path):
    with open(path) as f:
        rows = [line.rstrip("\n").split(",") for line in f]
    return rows[0], [[float(x) for x in row] for row in rows[1:]]


def mjcf_robots(cli, source, out_dir):
    """MuJoCo's humanoid (bodies with several joints): the export is one MJCF body per MuJoCo
    body, and with converged iterations the engines agree to rounding (the 1-dof map is exact
    per joint; few iterations leave coupled joints apart)."""
    scene = os.path.join(source, "examples", "humanoid_hold.yaml")
    r = run(cli, "compare-mujoco", scene, "--translate", "--solver", "pgs",
            "--position-iterations", "64", "--velocity-iterations", "1")
    m = re.search(r"largest relative difference: q " + NUMBER + ", qd " + NUMBER + ", force " +
                  NUMBER, r.stdout)
    check(r.returncode == 0 and m is not None and max(float(x) for x in m.groups()) < 1e-9,
          "compare-mujoco humanoid_hold (PGS 64/1) agrees within 1e-9 of the run's scale", r)
    r = run(cli, "compare-mujoco", scene)
    check(r.returncode == 0 and "mjMINVAL" not in r.stderr, "compare-mujoco humanoid_hold runs", r)
    xml = os.path.join(out_dir, "humanoid.xml")
    r = run(cli, "translate", scene, "--to", "mujoco", "--out", xml)
    check(r.returncode == 0, "translate humanoid_hold --to mujoco succeeds", r)
    if r.returncode == 0:
        import xml.etree.ElementTree as ET
        bodies = {b.get("name"): [j.get("name") for j in b.findall("joint")]
                  for b in ET.parse(xml).getroot().iter("body")}
        original = {b.get("name"): [j.get("name") for j in b.findall("joint")]
                    for b in ET.parse("/usr/share/mujoco/model/humanoid/humanoid.xml")
                    .getroot().iter("body")}
        original["torso"] = []  # welded: fixed_base
        check(bodies == original, f"the MJCF's bodies and their joints are MuJoCo's: {bodies}")
        r = run(cli, "info", xml)
        check(r.returncode == 0 and "21 dofs" in r.stdout, "the MJCF loads back (21 dofs)", r)


def mimic_gripper(cli, source):
    """The gripper's mimic rows reach MuJoCo as joint equalities. Literal drives (no joint
    damping): both engines hold knuckle = 12.5 finger - 0.1, so the knuckle's q difference is
    12.5 times the finger's (measured: 5.55e-2 = 12.5 x 4.44e-3). Translated drives: MuJoCo damps
    the finger after its constraint solve and the knuckle trails for a step (measured: 9.5e-2 of
    the scale; uncoupled, 1.2)."""
    scene = os.path.join(source, "tests", "data", "composition", "mimic_gripper.yaml")
    for mapping in ("--literal", "--translate"):
        r = run(cli, "compare-mujoco", scene, mapping)
        found = tables(r.stdout)
        check(r.returncode == 0 and len(found) == 1 and "knuckle" in found[0],
              f"compare-mujoco mimic_gripper {mapping}: a table with the knuckle", r)
        if r.returncode != 0 or len(found) != 1 or "knuckle" not in found[0]:
            continue
        knuckle, finger = found[0]["knuckle"][0], found[0]["left_finger"][0]
        if mapping == "--literal":
            check(abs(knuckle - 12.5 * finger) <= 0.02 * knuckle,
                  f"mimic_gripper literal: knuckle q difference {knuckle} = 12.5 x the "
                  f"finger's {finger}", r)
        else:
            check(found[0]["knuckle"][2] < 0.15,
                  f"mimic_gripper translated: knuckle relative q difference "
                  f"{found[0]['knuckle'][2]} < 0.15", r)


def round_trips(cli, source, out_dir):
    """scene -> MJCF (translate --to mujoco) -> scene (translate --to physx): the scene comes
    back key by key with the MJCF as its model, the robot keeps its name, and both scenes
    simulate alike."""
    import yaml
    for name, robot in (("slider.yaml", "slider"), ("arm7_tgs.yaml", "arm7"),
                        ("spherical_wrist.yaml", "spherical_wrist"),
                        ("humanoid_hold.yaml", "Humanoid"),
                        ("../tests/data/composition/mimic_gripper.yaml", "mimic_gripper")):
        scene = os.path.normpath(os.path.join(source, "examples", name))
        name = os.path.basename(name)
        xml = os.path.join(out_dir, "rt_" + name.replace(".yaml", ".xml"))
        back = os.path.join(out_dir, "rt_" + name)
        r = run(cli, "translate", scene, "--to", "mujoco", "--out", xml)
        check(r.returncode == 0, f"{name}: translate --to mujoco", r)
        r = run(cli, "translate", xml, "--to", "physx", "--out", back)
        check(r.returncode == 0 and "the one the MJCF was exported from" in r.stdout,
              f"{name}: translate --to physx restores the scene", r)
        if r.returncode != 0:
            continue
        with open(xml) as f:
            check(f'<mujoco model="{robot}">' in f.read(), f"{name}: the MJCF names the robot")
        with open(scene) as f:
            before = yaml.safe_load(f)
        with open(back) as f:
            after = yaml.safe_load(f)
        check(after.pop("model") == os.path.basename(xml), f"{name}: the model is the MJCF")
        for key, value in before.items():
            if key == "model":
                continue
            if key == "joints":  # the record adds what the MJCF cannot give back
                for joint, settings in value.items():
                    check(all(after[key][joint][k] == v for k, v in settings.items()),
                          f"{name}: joints.{joint} kept: {settings} in {after[key][joint]}")
            else:
                check(after.get(key) == value, f"{name}: {key} kept: {value} -> {after.get(key)}")
        runs = []
        for s in (scene, back):
            csv = os.path.join(out_dir, "rt_" + os.path.basename(s) + ("_a" if s == scene else "_b")
                               + ".csv")
            r = run(cli, "simulate", s, "--out", csv)
            check(r.returncode == 0, f"{name}: simulate {s}", r)
            runs.append(read_csv(csv) if r.returncode == 0 else None)
        if runs[0] and runs[1]:
            check(runs[0][0] == runs[1][0], f"{name}: the same CSV columns")
            scale = max(max(abs(x) for x in row) for row in runs[0][1])
            worst = max(abs(a - b) for ra, rb in zip(runs[0][1], runs[1][1]) for a, b in zip(ra, rb))
            check(len(runs[0][1]) == len(runs[1][1]) and worst <= 1e-10 * scale,
                  f"{name}: the round-tripped scene simulates as the original ({worst} of {scale})")


def urdf_geometry(cli, source, out_dir):
    """translate --to mujoco writes the URDF's visuals and collisions as geoms (mesh files
    resolved, --package for package://, COLLADA left out with a warning line); the export still
    round-trips to a scene that simulates as the original."""
    from xml.etree import ElementTree
    urdf = os.path.abspath(os.path.join(source, "tests", "data", "geometry.urdf"))
    scene = os.path.join(out_dir, "geom.yaml")
    with open(scene, "w") as f:
        f.write(f"model: {urdf}\nsteps: 60\ninitial: {{q: {{joint1: 0.3}}}}\n"
                "drives:\n  joint1: {type: force, stiffness: 200, damping: 20,\n"
                "           target: {sine: {amplitude: 0.4, frequency: 0.5}}}\n")
    xml = os.path.join(out_dir, "geom.xml")
    r = run(cli, "translate", scene, "--to", "mujoco", "--out", xml)
    check(r.returncode == 0 and "warning" not in r.stdout, "geometry.urdf: translated", r)
    if r.returncode == 0:
        root = ElementTree.parse(xml).getroot()
        check(root.find("compiler").get("inertiafromgeom") == "false",
              "geoms give no inertia")
        geoms = {g.get("name"): g for g in root.iter("geom")}
        # tests/data/geometry.urdf: box 0.4 0.3 0.1, cylinders r 0.04 / 0.05, sphere r 0.06.
        check(sorted(geoms) == ["base:collision0", "base:visual0", "link1:collision0",
                                "link1:visual0", "tool:visual0"], f"the five geoms: {list(geoms)}")
        if "base:visual0" in geoms and "tool:visual0" in geoms:
            check(geoms["base:visual0"].get("size") == "0.2 0.15 0.05", "box half extents")
            check(geoms["link1:visual0"].get("size") == "0.04 0.25", "cylinder radius, half length")
            check(geoms["tool:visual0"].get("contype") == "0" and
                  geoms["tool:visual0"].get("group") == "1", "a visual makes no contact")
            check(geoms["base:collision0"].get("group") == "0", "collisions in group 0")
        back = os.path.join(out_dir, "geom_back.yaml")
        r = run(cli, "translate", xml, "--to", "physx", "--out", back)
        check(r.returncode == 0, "geometry.urdf's MJCF back to a scene", r)
        runs = []
        for s in (scene, back):
            csv = s + ".csv"
            r = run(cli, "simulate", s, "--out", csv)
            check(r.returncode == 0, f"simulate {s}", r)
            runs.append(read_csv(csv) if r.returncode == 0 else None)
        if runs[0] and runs[1]:
            worst = max(abs(a - b) for ra, rb in zip(runs[0][1], runs[1][1]) for a, b in zip(ra, rb))
            check(worst <= 1e-10, f"geometry.urdf's round trip simulates alike ({worst})")
    r = run(cli, "translate", scene, "--to", "mujoco", "--out", xml + "2", "--package", "herb")
    one_line_error(r, ["--package 'herb'", "NAME=DIR"], "a --package without a folder")
    check(not os.path.exists(xml + "2"), "no MJCF written for a bad --package")
    # A mesh file MuJoCo cannot read is the input's fault: exit 2 naming the URDF and the file.
    with open(urdf) as f:
        text = f.read().replace('<sphere radius="0.06"/>', '<mesh filename="broken.stl"/>')
    with open(os.path.join(out_dir, "broken.urdf"), "w") as f:
        f.write(text)
    with open(os.path.join(out_dir, "broken.stl"), "w") as f:
        f.write("not an STL")
    broken = os.path.join(out_dir, "geom_broken.yaml")
    with open(broken, "w") as f:
        f.write("model: broken.urdf\nsteps: 10\n"
                "drives:\n  joint1: {type: force, stiffness: 200, damping: 20}\n")
    r = run(cli, "translate", broken, "--to", "mujoco", "--out", xml + "3")
    one_line_error(r, ["broken.urdf", "geometry", "broken.stl"], "a mesh MuJoCo cannot read")
    check(not os.path.exists(xml + "3"), "no MJCF written for a broken mesh")

    wam = "/usr/share/doc/dart/data/urdf/wam/wam.urdf"
    if not os.path.exists(wam):
        return
    scene = os.path.join(out_dir, "geom_wam.yaml")
    with open(scene, "w") as f:
        f.write(f"model: {wam}\nsteps: 10\ndrives:\n  /j1: {{type: force, stiffness: 100, "
                "damping: 10}\n")
    xml = os.path.join(out_dir, "geom_wam.xml")
    r = run(cli, "translate", scene, "--to", "mujoco", "--out", xml)
    check(r.returncode == 0 and "16 meshes of package 'herb_description' left out" in r.stdout,
          "WAM without --package: one warning line for the package", r)
    r = run(cli, "translate", scene, "--to", "mujoco", "--out", xml,
            "--package", "herb_description=" + os.path.dirname(wam))
    check(r.returncode == 0 and "8 COLLADA (.dae) meshes left out of the MJCF's drawn geoms "
          "(MuJoCo 2.2.2 cannot load them; 8 visual):" in r.stdout,
          "WAM: the COLLADA visuals are left out on one warning line", r)
    if r.returncode == 0:
        root = ElementTree.parse(xml).getroot()
        files = [m.get("file") for m in root.iter("mesh")]
        check(len(files) == 8 and all(f.endswith("_collision.STL") and os.path.isfile(f)
                                      for f in files), f"WAM: its 8 STL collisions: {files}")

    # The WAM with its COLLADA visuals as collisions, over a ground: the hulls reach MuJoCo as
    # inline vertex meshes (MuJoCo 2.2.2 reads no .dae) and compare-mujoco runs on it.
    scene = os.path.join(source, "tests", "data", "collada", "wam_dae_ground.yaml")
    xml = os.path.join(out_dir, "wam_dae.xml")
    r = run(cli, "translate", scene, "--to", "mujoco", "--out", xml)
    check(r.returncode == 0, "WAM with .dae collisions: translated", r)
    # The warning says what is left out: the drawn geoms; the collisions' hulls go in.
    check(" collision (their contact hulls go in as inline meshes with a ground or "
          "self-collision)):" in r.stdout and "left out of the MJCF's drawn geoms" in r.stdout,
          "WAM with .dae collisions: the warning names the drawn geoms as what is left out", r)
    if r.returncode == 0:
        root = ElementTree.parse(xml).getroot()
        inline = [m for m in root.iter("mesh") if m.get("vertex") and not m.get("file")]
        check(len(inline) == 8, f"WAM with .dae collisions: 8 inline hulls ({len(inline)})")
    r = run(cli, "compare-mujoco", scene, "--steps", "20")
    check(r.returncode == 0 and "translated" in r.stdout,
          "WAM with .dae collisions: compare-mujoco runs", r)


def main():
    cli, source, out_dir = sys.argv[1:4]
    os.makedirs(out_dir, exist_ok=True)
    scene = os.path.join(source, "examples", "slider.yaml")
    png = os.path.join(out_dir, "slider_mujoco_diff.png")
    if os.path.exists(png):
        os.remove(png)
    r = run(cli, "compare-mujoco", scene, "--plot", png)
    check(r.returncode == 0, "compare-mujoco slider succeeds", r)
    out = r.stdout
    check("(1 dof)" in out and "240 steps" in out and "solver pgs 4/1" in out,
          "the run is described", r)
    check("MuJoCo 2.2.2" in out and "integrator euler" in out, "MuJoCo's version and integrator", r)
    check("translated drives" in out and "literal drives" in out, "both mappings are run", r)
    found = tables(out)
    check(len(found) == 2 and all("slide" in t for t in found),
          "two tables with a row for slide", r)
    if len(found) == 2 and all("slide" in t for t in found):
        translated, literal = found[0]["slide"], found[1]["slide"]
        # PGS on one dof is reproduced term by term (docs/mujoco_bridge.md, eq. B8): only rounding
        # separates the engines; the literal copy misses the implicit share of the stiffness.
        check(translated[0] < 1e-9, f"translated q difference {translated[0]} < 1e-9", r)
        check(translated[6] < 1e-6, f"translated force difference {translated[6]} < 1e-6 N", r)
        check(literal[0] > 1e-4, f"literal q difference {literal[0]} > 1e-4", r)
    check(f"plot: {png}" in out, "the plot is reported", r)
    if os.path.exists(png):
        with open(png, "rb") as f:
            check(f.read(8) == b"\x89PNG\r\n\x1a\n", "the plot is a PNG")
    else:
        check(False, "the plot is written")

    xml = os.path.join(out_dir, "slider_translated.xml")
    r = run(cli, "translate", scene, "--to", "mujoco", "--out", xml)
    check(r.returncode == 0, "translate --to mujoco succeeds", r)
    check(re.search(r"^\s+slide\s.*exact", r.stdout, re.M) is not None,
          "the slide's drive is exact", r)
    if os.path.exists(xml):
        with open(xml) as f:
            text = f.read()
        check(text.startswith("<mujoco") and 'name="slide:position"' in text,
              "the MJCF holds the actuator")
        # kd + dt kp for slider.yaml: 40 + 400 / 60 (eq. B7).
        check('damping="46.666666666666' in text, "the joint damping is kd + dt kp")

    # --to physx: an MJCF slider (position actuator, joint damping 40 >= dt kp = 15) to a scene
    # that `simulate` runs; PGS reproduces MuJoCo's Euler step exactly (eq. B11).
    mjcf = os.path.join(out_dir, "mj_slider.xml")
    with open(mjcf, "w") as f:
        f.write('<mujoco><option timestep="0.016666666666666666"/><worldbody><body name="cart">'
                '<joint name="slide" type="slide" axis="1 0 0" damping="40"/>'
                '<inertial pos="0 0 0" mass="2" diaginertia="0.01 0.01 0.01"/></body></worldbody>'
                '<actuator><position joint="slide" kp="900"/></actuator></mujoco>\n')
    translated = os.path.join(out_dir, "mj_slider_scene.yaml")
    r = run(cli, "translate", mjcf, "--to", "physx", "--out", translated)
    check(r.returncode == 0, "translate --to physx succeeds", r)
    check(re.search(r"^\s+slide\s.*\s900\s.*\s25\s.*exact", r.stdout, re.M) is not None,
          "kp 900 and damping 40 - dt kp = 25, exact", r)
    r = run(cli, "simulate", translated)
    check(r.returncode == 0, "the translated scene runs", r)

    slider_urdf = os.path.abspath(os.path.join(source, "examples", "slider.urdf"))
    for integration in ("explicit", "implicit"):
        actuated = os.path.join(out_dir, f"mj_actuated_{integration}.yaml")
        with open(actuated, "w") as f:
            f.write(f"model: {slider_urdf}\nsteps: 10\ndrives:\n"
                    "  slide: {type: none, actuator: {type: ideal_pd, stiffness: 100, "
                    f"integration: {integration}}}}}\n")
        for command in (["compare-mujoco", actuated], ["translate", actuated, "--to", "mujoco",
                                                       "--out", os.path.join(out_dir, "x.xml")]):
            r = run(cli, *command)
            one_line_error(r, [f"mj_actuated_{integration}.yaml", "joint slide",
                               f"{integration} actuator"],
                           f"{command[0]} with an {integration} actuator")
    # The step guard: MuJoCo steps unguarded, which both tools say in a note.
    guarded = os.path.join(out_dir, "mj_guarded.yaml")
    with open(guarded, "w") as f:
        f.write(f"model: {slider_urdf}\nsteps: 10\n"
                "drives: {slide: {type: force, stiffness: 10, damping: 1}}\nguard: {}\n")
    for command in (["compare-mujoco", guarded], ["translate", guarded, "--to", "mujoco",
                                                  "--out", os.path.join(out_dir, "g.xml")]):
        r = run(cli, *command)
        check(r.returncode == 0 and "note: step guard not exported: MuJoCo steps unguarded" in r.stdout,
              f"{command[0]} of a guarded scene notes the guard", r)
    undriven = os.path.join(out_dir, "mj_undriven.yaml")
    with open(undriven, "w") as f:
        f.write(f"model: {slider_urdf}\nsteps: 10\n")
    r = run(cli, "translate", undriven, "--to", "mujoco", "--out", os.path.join(out_dir, "y.xml"))
    one_line_error(r, ["mj_undriven.yaml", "nothing to translate"], "translate without drives")
    check(not os.path.exists(os.path.join(out_dir, "y.xml")), "no MJCF written without drives")

    # Past MuJoCo's explicit limit (the arm demo: kp dt^2/m from 15 to 1331 against 4) the tool
    # says that the literal copy is unstable, while the translation stays exact.
    arm = os.path.join(source, "examples", "arm7_tgs.yaml")
    r = run(cli, "translate", arm, "--to", "mujoco", "--out", os.path.join(out_dir, "arm7.xml"))
    check(r.returncode == 0, "translate arm7_tgs succeeds", r)
    rows = re.findall(r"^\s+joint\d\s.*$", r.stdout, re.M)
    check(len(rows) == 7 and all("exact; literal copy unstable in MuJoCo" in x for x in rows),
          "every arm joint: exact, literal copy unstable", r)

    # Numbers that do not fit (issue 36): a gear whose gain gear^2 overflows, refused naming the
    # file, the actuator and the gear, and no scene written with stiffness inf.
    gear = os.path.join(out_dir, "mj_gear.xml")
    with open(gear, "w") as f:
        f.write('<mujoco><worldbody><body name="cart"><joint name="slide" type="slide"/>'
                '<inertial pos="0 0 0" mass="2" diaginertia="0.01 0.01 0.01"/></body></worldbody>'
                '<actuator><position name="push" joint="slide" kp="900" gear="1e200"/>'
                '</actuator></mujoco>\n')
    gear_scene = os.path.join(out_dir, "mj_gear.yaml")
    r = run(cli, "translate", gear, "--to", "physx", "--out", gear_scene)
    one_line_error(r, ["mj_gear.xml", "actuator 'push'", "gear 1e+200", "= inf"], "a gear of 1e200")
    check(not os.path.exists(gear_scene), "no scene written for a gear of 1e200")
    # Targets MuJoCo would zero (its ctrl beyond 1e10): the ctrl kp x_T + kd v_T here is
    # x_T + (kd / kp) v_T = 1e5 * 1e6 = 1e11, refused naming the joint, not compared with ctrl 0.
    big_ctrl = os.path.join(out_dir, "mj_big_ctrl.yaml")
    with open(big_ctrl, "w") as f:
        f.write(f"model: {slider_urdf}\nsteps: 10\ndrives:\n"
                "  slide: {type: force, stiffness: 1e-6, damping: 1e-1, target_velocity: 1e6}\n")
    r = run(cli, "compare-mujoco", big_ctrl, "--translate")
    one_line_error(r, ["mj_big_ctrl.yaml", "joint slide", "ctrl", "beyond the 1e+10"],
                   "a ctrl MuJoCo would zero")
    # A target beyond the representable range (docs/math/implicit_drives.md, eq. T3).
    far = os.path.join(out_dir, "mj_far_target.yaml")
    with open(far, "w") as f:
        f.write(f"model: {slider_urdf}\nsteps: 10\ndrives:\n"
                "  slide: {type: force, stiffness: 100, damping: 1, target_position: 2e10}\n")
    r = run(cli, "compare-mujoco", far)
    one_line_error(r, ["mj_far_target.yaml", "drives.slide.target_position = 2e10",
                       "beyond +-1e6"], "a target of 2e10")

    # Verdicts come from the measured run (docs/mujoco_bridge.md, "Verdicts"): the slider agrees
    # and is exact; on arm7_pgs every drive saturates and the run differs, so no joint is exact.
    r = run(cli, "compare-mujoco", scene, "--translate")
    check(re.search(r"^\s+slide\s.*exact \(1-dof map and run\)$", r.stdout, re.M) is not None,
          "the slider's verdict is exact", r)
    r = run(cli, "compare-mujoco", os.path.join(source, "examples", "arm7_pgs.yaml"), "--translate")
    verdicts = re.findall(r"^\s+joint\d\s.*\s(differs by (\S+) of the scale: (.*))$", r.stdout, re.M)
    check(r.returncode == 0 and len(verdicts) == 7 and "exact" not in r.stdout,
          "arm7_pgs: no joint called exact", r)
    table = tables(r.stdout)
    for whole, figure, why in verdicts:
        check(float(figure) > 0.1 and why.startswith(("max_force saturates", "coupled joints")),
              f"arm7_pgs verdict: {whole}")
    check(any(why.startswith("max_force saturates") for _, _, why in verdicts),
          "arm7_pgs: a saturating drive is named", r)
    if table:
        worst = max(v[2] for v in table[0].values())
        check(abs(max(float(f) for _, f, _ in verdicts) - worst) <= 0.01 * worst + 0.005,
              f"the verdicts' largest figure is the table's largest relative q difference {worst}")
    # Spherical joints: one line naming the scene and the joint.
    wrist = os.path.join(source, "examples", "spherical_wrist.yaml")
    one_line_error(run(cli, "compare-mujoco", wrist),
                   ["spherical_wrist.yaml", "joint 'wrist' is spherical"], "a spherical wrist")

    # A ground beside collision shapes travels to MuJoCo: the plane and the shape as geoms that
    # collide with each other only, contacts on.
    grounded = os.path.join(out_dir, "slider_ground.yaml")
    with open(grounded, "w") as f:
        f.write(f"model: {os.path.join(source, 'examples', 'slider.urdf')}\nfixed_base: true\n"
                "dt: 0.016666666666666666\nsteps: 60\n"
                "drives: {slide: {type: force, stiffness: 400, damping: 40, "
                "target_position: -0.3}}\n"  # below the ground: the pad lands and stays
                "ground: {height: -0.2, static_friction: 0.7}\n"
                "shapes: [{link: carriage, name: pad, type: sphere, radius: 0.05, "
                "static_friction: 0.3}]\n")
    r = run(cli, "compare-mujoco", grounded, "--translate")
    check(r.returncode == 0 and "contacts with the ground on" in r.stdout
          and "note: ground contacts as MuJoCo's soft contacts" in r.stdout,
          "compare-mujoco carries the ground", r)
    grounded_xml = os.path.join(out_dir, "grounded.xml")
    r = run(cli, "translate", grounded, "--to", "mujoco", "--out", grounded_xml)
    check(r.returncode == 0, "translate --to mujoco with a ground", r)
    with open(grounded_xml) as f:
        xml = f.read()
    check('<flag contact="disable"/>' not in xml
          and '<geom name="featherdrive_ground" type="plane" size="0 0 1" pos="0 0 -0.2"' in xml
          and '<geom name="shape:0:pad" type="sphere" size="0.05"' in xml
          and 'friction="0.5 0 0"' in xml,  # the pair's average, 0.5 (0.3 + 0.7)
          "the MJCF has the plane and the shape, contacts on:\n" + xml)

    r = run(cli, "compare-mujoco", scene, "--translate", "--literal")
    one_line_error(r, ["--translate and --literal"], "both mappings chosen")
    r = run(cli, "translate", scene, "--to", "mujoco", "--out", scene)
    one_line_error(r, ["--out"], "--out naming the scene")
    r = run(cli, "compare-mujoco", scene, "--integrator", "rk4")
    one_line_error(r, ["--integrator"], "an unknown integrator")

    mimic_gripper(cli, source)
    mjcf_robots(cli, source, out_dir)
    round_trips(cli, source, out_dir)
    urdf_geometry(cli, source, out_dir)

    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
