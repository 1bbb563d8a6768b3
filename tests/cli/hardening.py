#!/usr/bin/python3
"""The command line against hostile files, paths, signals and numbers (issue 16): non-regular or
huge inputs, outputs that name an input or a device, --plot temporaries, SIGINT / SIGTERM,
integer options, overflowing reports, names that need escaping, a PhysX scale of 0, plot errors.

usage: hardening.py FEATHERDRIVE SOURCE_DIR OUT_DIR
"""
import csv
import io
import json
import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import time

failures = []
CLI = SOURCE = WORK = TMP = None


def env(**changes):
    e = dict(os.environ)
    e["TMPDIR"] = TMP  # every temporary must land (and be removed) here
    e.pop("FEATHERDRIVE_PHYSX_DIR", None)
    e.update(changes)
    return e


def run(*args, cwd=None, **changes):
    return subprocess.run([CLI, *args], capture_output=True, text=True, timeout=60, cwd=cwd,
                          env=env(**changes))


def check(condition, what, result=None):
    if not condition:
        detail = ""
        if result:
            detail = f"\n  rc={result.returncode} stdout={result.stdout!r} stderr={result.stderr!r}"
        failures.append(what + detail)


def one_line_error(result, code, text, what):
    check(result.returncode == code, f"{what}: exit code {code}", result)
    check(len(result.stderr.strip().splitlines()) == 1, f"{what}: one line on stderr", result)
    check(text in result.stderr, f"{what}: stderr holds {text!r}", result)


def no_temporaries(what):
    check(os.listdir(TMP) == [], f"{what}: nothing left in TMPDIR: {os.listdir(TMP)}")
    left = [n for n in os.listdir(WORK) if re.match(r"^\..*\.[A-Za-z0-9]{6}$", n)]
    check(left == [], f"{what}: no temporary output left in {WORK}: {left}")


def read(path, mode="r"):
    with open(path, mode) as f:
        return f.read()


def write(path, text):
    with open(path, "w") as f:
        f.write(text)
    return path


def w(name):
    return os.path.join(WORK, name)


def slider_copy():
    """The slider scene and its URDF copied into WORK: inputs the tests may try to clobber."""
    shutil.copy(os.path.join(SOURCE, "examples", "slider.urdf"), w("slider.urdf"))
    text = read(os.path.join(SOURCE, "examples", "slider.yaml"))
    return write(w("s.yaml"), text.replace("steps: 240", "steps: 20"))


def non_regular_inputs():
    scene = slider_copy()
    fifo = w("pipe.yaml")
    os.mkfifo(fifo)
    big = w("big.yaml")
    with open(big, "wb") as f:
        f.truncate(64 * 1024 * 1024 + 1)  # sparse
    os.mkdir(w("folder.urdf"))
    cases = [(WORK, "is a directory"), (fifo, "is not a regular file (a FIFO)"),
             ("/dev/zero", "is not a regular file (a character device)"),
             (big, "is larger than 64 MiB (67108865 bytes)")]
    for path, why in cases:
        one_line_error(run("simulate", path), 2, f"{path}: {why}", f"simulate {path}")
        one_line_error(run("compare-physx", path), 2, f"{path}: {why}", f"compare-physx {path}")
        one_line_error(run("info", path), 2, f"{path}: {why}", f"info {path}")
        one_line_error(run("simulate", scene, "--load-state", path), 2, f"{path}: {why}",
                       f"--load-state {path}")
    # A scene whose model is not a regular file: refused by the URDF reader, without a read.
    for model, why in ((w("folder.urdf"), "is a directory"),
                       (fifo, "is not a regular file (a FIFO)"),
                       ("/dev/zero", "is not a regular file (a character device)")):
        s = write(w("model.yaml"), f"model: {model}\nsteps: 1\n")
        one_line_error(run("simulate", s), 2, f"{model}: {why}", f"a scene with model {model}")
    one_line_error(run("simulate", w("missing.yaml")), 2,
                   f"{w('missing.yaml')}: cannot open the file: No such file or directory",
                   "a missing scene")
    os.remove(fifo)
    os.remove(big)
    os.rmdir(w("folder.urdf"))


def outputs_never_clobber_inputs():
    scene = slider_copy()
    before = read(scene)
    ckpt = w("s.ckpt")
    r = run("simulate", scene, "--save-state", ckpt)
    check(r.returncode == 0, "a checkpoint to resume from", r)
    ckpt_bytes = read(ckpt, "rb")
    os.makedirs(w("sub"), exist_ok=True)
    os.symlink(scene, w("link.yaml"))
    os.link(scene, w("hard.yaml"))
    png_scene = write(w("scene.png"), before)  # a scene file that --plot could name
    cases = [
        (["--out", scene], "is the scene"),
        (["--out", os.path.join(WORK, "sub", "..", "s.yaml")], "is the scene"),
        (["--out", "./s.yaml"], "is the scene"),
        (["--out", w("link.yaml")], "is the scene"),
        (["--out", w("hard.yaml")], "is the scene"),
        (["--save-state", scene], "is the scene"),
        (["--out", w("slider.urdf")], "is the scene's model"),
        (["--save-state", w("slider.urdf")], "is the scene's model"),
        (["--load-state", ckpt, "--save-state", ckpt], "is the --load-state checkpoint"),
        (["--load-state", ckpt, "--out", w("sub/../s.ckpt")], "is the --load-state checkpoint"),
        (["--out", w("a.csv"), "--save-state", w("sub/../a.csv")],
         "two outputs cannot share a file"),
        (["--out", w("x.png"), "--plot", w("x.png")], "two outputs cannot share a file"),
    ]
    for extra, text in cases:
        r = run("simulate", scene, *extra, cwd=WORK)
        one_line_error(r, 2, text, f"simulate {' '.join(extra)}")
        check(r.stdout == "", f"{extra}: refused before simulating", r)
    r = run("simulate", png_scene, "--plot", png_scene)
    one_line_error(r, 2, "--plot " + png_scene + ": is the scene", "--plot naming the scene")
    check(read(scene) == before and read(png_scene) == before, "the scene files are untouched")
    check(read(ckpt, "rb") == ckpt_bytes, "the checkpoint is untouched")
    check(not os.path.exists(w("a.csv")), "no output of a refused run")
    # Targets that are not regular files are never replaced.
    fifo = w("pipe.csv")
    os.mkfifo(fifo)
    os.mkdir(w("folder.csv"))
    for option, target in (("--out", "/dev/null"), ("--save-state", "/dev/null"), ("--out", fifo),
                           ("--save-state", fifo), ("--out", w("folder.csv"))):
        one_line_error(run("simulate", scene, option, target), 2,
                       f"{target}: is not a regular file; refusing to replace it",
                       f"{option} {target}")
    check(stat.S_ISFIFO(os.stat(fifo).st_mode) and os.path.isdir(w("folder.csv")),
          "the FIFO and the folder are still there")
    check(stat.S_ISCHR(os.stat("/dev/null").st_mode), "/dev/null is still a device")
    # A successful run replaces a regular file whole, leaving no temporary.
    write(w("a.csv"), "old")
    r = run("simulate", scene, "--out", w("a.csv"), "--save-state", w("a.ckpt"))
    check(r.returncode == 0 and read(w("a.csv")).startswith("step,t,q:slide"),
          "--out replaces a file", r)
    # An output that cannot be written: exit 1, one line, nothing left behind.
    write(w("plain"), "")
    one_line_error(run("simulate", scene, "--out", w("plain/x.csv")), 1,
                   f"{w('plain/x.csv')}: cannot write the trajectory", "--out under a file")
    one_line_error(run("simulate", scene, "--save-state", w("plain/x.ckpt")), 1,
                   f"{w('plain/x.ckpt')}: cannot write the checkpoint", "--save-state under a file")
    no_temporaries("outputs")
    for name in ("pipe.csv", "link.yaml", "hard.yaml", "scene.png", "plain", "a.csv", "a.ckpt"):
        os.remove(w(name))
    os.rmdir(w("folder.csv"))


def fake_python(name, body):
    """An executable standing in for python3: gets the plot script's argv."""
    path = w(name)
    write(path, "#!/usr/bin/python3\nimport json, os, sys\n" + body)
    os.chmod(path, 0o755)
    return path


def plots():
    scene = slider_copy()
    # The fake records what it was given and writes a PNG signature to the last path.
    record = w("argv.json")
    fake = fake_python("fake_python", f"""
args = sys.argv[1:]
csvs = args[args.index('--') + 1:-1]
info = {{'args': args, 'dirs': [oct(os.stat(os.path.dirname(c)).st_mode & 0o777) for c in csvs],
        'lines': [open(c).read().count('\\n') for c in csvs]}}
json.dump(info, open({record!r}, 'w'))
open(args[-1], 'wb').write(b'\\x89PNG\\r\\n\\x1a\\n')
""")
    r = run("simulate", scene, "--plot", w("p.png"), FEATHERDRIVE_PYTHON=fake)
    check(r.returncode == 0 and read(w("p.png"), "rb").startswith(b"\x89PNG"),
          "a plot through the fake", r)
    if os.path.exists(record):
        info = json.load(open(record))
        args = info["args"]
        check("--" in args and args.index("--") == 2 and args[1].startswith("--title="),
              f"the paths come after --: {args}")
        csvs = args[args.index("--") + 1:-1]
        check(len(csvs) == 2 and all(c.startswith(TMP + os.sep + "featherdrive-") for c in csvs),
              f"the CSVs are in a private folder under TMPDIR: {csvs}")
        check(info["dirs"] == ["0o700", "0o700"], f"the folder is private: {info['dirs']}")
        check(info["lines"] == [22, 22], f"both CSVs are complete: {info['lines']}")
        check(os.path.dirname(args[-1]) == WORK and args[-1] != w("p.png"),
              f"the PNG is written to a temporary beside the target: {args[-1]}")
    no_temporaries("--plot")
    # A planted symlink in TMPDIR is never followed: nothing in TMPDIR is written but our folder.
    victim = write(w("victim"), "precious")
    for i in range(3):
        os.symlink(victim, os.path.join(TMP, f"featherdrive-planted-{i}"))
    r = run("simulate", scene, "--plot", w("p.png"), FEATHERDRIVE_PYTHON=fake)
    check(r.returncode == 0 and read(victim) == "precious", "a planted symlink is not followed", r)
    for i in range(3):
        os.remove(os.path.join(TMP, f"featherdrive-planted-{i}"))
    # The script failing: its last stderr line, exit 1, no PNG, no temporaries.
    failing = fake_python("failing_python",
                          "print('Traceback (most recent call last):', file=sys.stderr)\n"
                          "print('  File x', file=sys.stderr)\n"
                          "sys.exit('ValueError: could not convert string to float')\n")
    os.remove(w("p.png"))
    r = run("simulate", scene, "--plot", w("p.png"), FEATHERDRIVE_PYTHON=failing)
    one_line_error(r, 1,
                   f"plotting {w('p.png')} failed: ValueError: could not convert string to float",
                   "a failing plot script")
    check("Traceback" not in r.stderr and not os.path.exists(w("p.png")), "no traceback, no PNG", r)
    # A python without matplotlib: Debian's without its site packages, and the pyenv one on PATH.
    no_mpl = w("python_without_site")
    write(no_mpl, "#!/bin/sh\nexec /usr/bin/python3 -S \"$@\"\n")
    os.chmod(no_mpl, 0o755)
    pythons = [no_mpl]
    other = shutil.which("python3")
    has_mpl = other and subprocess.run([other, "-c", "import matplotlib"],
                                       capture_output=True).returncode == 0
    if other and not has_mpl:
        pythons.append(other)
    for python in pythons:
        r = run("simulate", scene, "--plot", w("p.png"), FEATHERDRIVE_PYTHON=python)
        one_line_error(r, 1, "cannot import matplotlib", f"--plot with {python}")
        check("Traceback" not in r.stderr and not os.path.exists(w("p.png")),
              "no traceback, no PNG", r)
    r = run("simulate", scene, "--plot", w("p.png"), FEATHERDRIVE_PYTHON=w("no-such-python"))
    one_line_error(r, 1, "no-such-python could not be run", "a python that does not exist")
    # Extensions are checked before anything runs.
    for png in ("out.jpg", "out", "out.png.csv", "out.pdf"):
        r = run("simulate", scene, "--plot", w(png), "--out", w("never.csv"))
        one_line_error(r, 2, f"--plot {w(png)}: the plot must be a .png file", f"--plot {png}")
        check(not os.path.exists(w("never.csv")), f"--plot {png}: nothing ran")
        one_line_error(run("compare-physx", scene, "--plot", w(png)), 2,
                       "the plot must be a .png file", f"compare-physx --plot {png}")
    # Paths beginning with '-' are paths, with the real plot script.
    r = run("simulate", scene, "--out=-traj.csv", "--plot=-plot.PNG", cwd=WORK)
    check(r.returncode == 0 and read(w("-plot.PNG"), "rb").startswith(b"\x89PNG"),
          "paths beginning with -", r)
    check(read(w("-traj.csv")).count("\n") == 22, "the trajectory beginning with - is whole")
    no_temporaries("plots")
    for name in ("-plot.PNG", "-traj.csv", "victim", "argv.json"):
        os.remove(w(name))


def wait_for_growth(directory, pattern, proc):
    """Waits until a file matching pattern in directory has data (or the process ended)."""
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and proc.poll() is None:
        for root, _, files in os.walk(directory):
            for name in files:
                if re.match(pattern, name) and os.path.getsize(os.path.join(root, name)) > 200000:
                    return True
        time.sleep(0.02)
    return False


def signals():
    scene = slider_copy()
    for sig, code, name in ((signal.SIGINT, 130, "SIGINT"), (signal.SIGTERM, 143, "SIGTERM")):
        out = w(f"long_{name}.csv")
        proc = subprocess.Popen([CLI, "simulate", scene, "--steps", "10000000", "--out", out,
                                 "--save-state", w("never.ckpt")],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=env())
        grew = wait_for_growth(WORK, rf"^\.long_{name}\.csv\.", proc)
        check(grew, f"{name}: the trajectory's temporary grows")
        proc.send_signal(sig)
        stdout, stderr = proc.communicate(timeout=60)
        result = subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)
        check(proc.returncode == code, f"{name}: exit {code}", result)
        m = re.search(rf"featherdrive: interrupted at step (\d+) of 10000000 \(signal {name}\); "
                      rf"the trajectory {re.escape(out)} holds steps 0\.\.(\d+)$", stderr.strip())
        check(m is not None and len(stderr.strip().splitlines()) == 1,
              f"{name}: one line saying where", result)
        with open(out, newline="") as f:
            rows = list(csv.reader(f))
        check(all(len(row) == len(rows[0]) for row in rows),
              f"{name}: every row has the header's columns")
        check(read(out).endswith("\n"), f"{name}: the last row is whole")
        if m:
            n = int(m.group(1))
            check(m.group(2) == m.group(1) and len(rows) == n + 2 and rows[-1][0] == str(n),
                  f"{name}: the CSV holds steps 0..{n}: {len(rows) - 1} rows, last {rows[-1][0]}")
        check(not os.path.exists(w("never.ckpt")), f"{name}: no checkpoint after an interrupt")
        no_temporaries(name)
        os.remove(out)
    # Only a plot wanted: the trajectory is a temporary in TMPDIR, removed at the interrupt.
    proc = subprocess.Popen([CLI, "simulate", scene, "--steps", "10000000",
                             "--plot", w("never.png")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env())
    check(wait_for_growth(TMP, r"^trajectory\.csv$", proc),
          "plot only: the temporary trajectory grows")
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    result = subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)
    one_line_error(result, 130, "(signal SIGINT); no trajectory was written", "plot only, SIGINT")
    check(not os.path.exists(w("never.png")), "no plot after an interrupt")
    no_temporaries("plot only, SIGINT")


def integers():
    scene = slider_copy()
    cases = [
        (["--steps", "-5"], "--steps = -5: must be between 0 and 2147483647"),
        (["--steps", "2147483648"], "--steps = 2147483648: must be between 0 and 2147483647"),
        (["--steps", "99999999999999999999999"],
         "--steps = 99999999999999999999999: must be between 0"),
        (["--steps", "1e3"], "--steps = 1e3: must be an integer between 0 and 2147483647"),
        (["--steps", "many"], "--steps = many: must be an integer"),
        (["--steps", ""], "--steps = : must be an integer"),
        (["--steps", "5x"], "--steps = 5x: must be an integer"),
        (["--position-iterations", "4294967297"],
         "--position-iterations = 4294967297: must be between 1 and 1000000"),
        (["--position-iterations", "0"],
         "--position-iterations = 0: must be between 1 and 1000000"),
        (["--position-iterations", "-4294967295"],
         "--position-iterations = -4294967295: must be between"),
        (["--velocity-iterations", "4294967296"],
         "--velocity-iterations = 4294967296: must be between 0 and 1000000"),
        (["--velocity-iterations", "-1"],
         "--velocity-iterations = -1: must be between 0 and 1000000"),
        (["--velocity-iterations", "1.5"], "--velocity-iterations = 1.5: must be an integer"),
    ]
    for extra, text in cases:
        for command in ("simulate", "compare-physx"):
            r = run(command, scene, *extra)
            one_line_error(r, 2, text, f"{command} {' '.join(extra)}")
            check(len(r.stderr) < 160, f"{command} {extra}: a short line", r)
    r = run("simulate", scene, "--steps", "+3", "--position-iterations", "1000000",
            "--velocity-iterations", "0")
    check(r.returncode == 0 and "3 steps" in r.stdout
          and "1000000 position / 0 velocity" in r.stdout,
          "integers at the bounds run", r)


def reports():
    """RMS errors of targets near the largest double: their sum of squares overflows (and one
    of 1e-200 underflows), yet with q at rest the error is the target at every step."""
    scene = write(w("huge.yaml"), f"model: {os.path.join(SOURCE, 'examples', 'chain3.urdf')}\n"
                  "gravity: [0, 0, 0]\ndt: 0.01\nsteps: 50\n"
                  "drive_defaults: {type: force, stiffness: 0, damping: 1}\n"
                  "drives: {joint1: {target_position: 1e308}, joint2: {target_position: -1e200},\n"
                  "         joint3: {target_position: 1e-200}}\n")
    r = run("simulate", scene)
    check(r.returncode == 0, "the huge targets run", r)
    for joint, value in (("joint1", "1.000e+308"), ("joint2", "-1.000e+200"),
                         ("joint3", "1.000e-200")):
        rms = value.lstrip("-")
        m = re.search(rf"^\s+{joint}\s+force\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s", r.stdout, re.M)
        check(m is not None and m.group(1) == value and m.group(2) == rms,
              f"{joint}: final error {value} and rms {rms}: {m.group(0) if m else r.stdout}")
    check("inf" not in r.stdout and "nan" not in r.stdout, "no inf or nan in the summary", r)


def names_and_physx_scale():
    """Joint names with commas, quotes and backslashes: the CSV header stays aligned, the JSON
    handed to PhysX reads back (a fake node parses it with Python's json), and a PhysX run that
    stays at 0 gives an infinite relative difference, not 0."""
    urdf = read(os.path.join(SOURCE, "examples", "pendulum.urdf"))
    odd = 'hinge, "the" \\one\\'
    urdf = urdf.replace('name="hinge"', 'name="hinge, &quot;the&quot; \\one\\"')
    write(w("odd.urdf"), urdf)
    scene = write(w("odd.yaml"), "model: odd.urdf\ndt: 0.01\nsteps: 5\ninitial: {q: {'" +
                  odd.replace("'", "''") + "': 1.0}}\n")
    r = run("simulate", scene, "--out", w("odd.csv"))
    check(r.returncode == 0, "a joint name with a comma and quotes simulates", r)
    if r.returncode == 0:
        with open(w("odd.csv"), newline="") as f:
            rows = list(csv.reader(f))
        check(rows[0] == ["step", "t", "q:" + odd, "qd:" + odd, "f:" + odd],
              f"the header: {rows[0]}")
        check(all(len(row) == 5 for row in rows) and len(rows) == 7, "every row has 5 columns")
    # The fake PhysX: node is a Python script that reads the scene with json and answers zeros.
    bin_dir, physx = w("fakebin"), w("fakephysx")
    os.makedirs(bin_dir, exist_ok=True)
    os.makedirs(os.path.join(physx, "node_modules", "physx-js-webidl"), exist_ok=True)
    for f in ("harness.js", "node_modules/physx-js-webidl/physx-js-webidl.mjs",
              "node_modules/physx-js-webidl/physx-js-webidl.wasm"):
        write(os.path.join(physx, f), "")
    seen = w("seen.json")
    node = os.path.join(bin_dir, "node")
    write(node, f"""#!/usr/bin/python3
import csv, json, sys
scene = json.load(open(sys.argv[2], encoding='utf-8'))
json.dump(scene, open({seen!r}, 'w'))
names = [l['joint']['name'] for l in scene['links'][1:]]
with open(sys.argv[3], 'w', newline='') as f:
    out = csv.writer(f, lineterminator='\\n')
    out.writerow(['step', 't'] + [p + n for p in ('q:', 'qd:', 'f:') for n in names])
    for k in range(scene['steps'] + 1):
        out.writerow([k, k * scene['dt']] + [0] * (3 * len(names)))
""")
    os.chmod(node, 0o755)
    r = run("compare-physx", scene, "--plot", w("cmp.png"),
            PATH=bin_dir + os.pathsep + os.environ.get("PATH", ""), FEATHERDRIVE_PHYSX_DIR=physx)
    check(r.returncode == 0, "compare-physx against the fake PhysX", r)
    # The differences' CSV (quoted header) read by the real plot script.
    check(os.path.exists(w("cmp.png")) and read(w("cmp.png"), "rb").startswith(b"\x89PNG"),
          "the differences of odd names are plotted", r)
    if os.path.exists(seen):
        s = json.load(open(seen))
        check(s["links"][1]["joint"]["name"] == odd and list(s["initial"]["q"]) == [odd],
              f"the JSON names the joint exactly: {s['links'][1]['joint']['name']!r}")
        check(s["gravity"] == [0, 0, -9.81], f"gravity survives the names: {s['gravity']}")
    # The pendulum swings (q, qd differ from PhysX's zeros); no drive, so both forces are 0.
    m = re.search(r"largest relative difference: q (\S+), qd (\S+), force (\S+)", r.stdout)
    check(m is not None and m.groups() == ("inf", "inf", "0.0e+00"),
          f"differences against PhysX's scale of 0 are inf: {m.groups() if m else r.stdout}")
    row = re.search(r"^\s+hinge, \"the\" \\one\\\s+(\S+)\s+(\d+)\s+(\S+)\s+(\S+)\s+(\d+)\s+(\S+)",
                    r.stdout, re.M)
    check(row is not None and float(row.group(1)) > 0.01
          and row.group(3) == "inf" and row.group(6) == "inf",
          f"the joint's row: a difference and a relative inf: {row.groups() if row else r.stdout}")
    check("relative to a scale of 0, any difference is inf" in r.stdout,
          "the scale of 0 is explained", r)
    shutil.rmtree(bin_dir)
    shutil.rmtree(physx)
    no_temporaries("compare-physx")


def deep_and_long_robots():
    # Stack depth the input controls: 100 000 nested elements are refused before the XML reader
    # recurses; a 10 000-link chain is described (no recursion in the printer, linear output).
    deep = write(w("deep.urdf"), '<robot name="r">' + "<a>" * 100000 + "</a>" * 100000 + "</robot>\n")
    one_line_error(run("info", deep), 2, f"{deep}: line 1: elements nested deeper than 100",
                   "info on a 100 000-deep URDF")
    links = ['<link name="l0"/>']
    joints = []
    for i in range(1, 10001):
        links.append(f'<link name="l{i}"><inertial><mass value="1"/>'
                     '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>')
        joints.append(f'<joint name="j{i}" type="revolute"><parent link="l{i - 1}"/>'
                      f'<child link="l{i}"/><origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>'
                      '<limit lower="-1" upper="1" effort="10" velocity="1"/></joint>')
    chain = write(w("chain.urdf"), '<robot name="chain">' + "".join(links + joints) + "</robot>\n")
    result = run("info", chain)
    check(result.returncode == 0, "info on a 10 000-link chain: exit 0", result)
    check("l10000" in result.stdout, "info on a 10 000-link chain: the last link is shown", result)
    # Indentation capped at depth 32: linear output (2 spaces a level would make it 300 MB).
    size = len(result.stdout)
    check(size < 1000 * 10000, f"info on a 10 000-link chain: {size} bytes, linear in the links")


def main():
    global CLI, SOURCE, WORK, TMP
    CLI, SOURCE, out_dir = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
    CLI = os.path.abspath(CLI)
    WORK = os.path.abspath(os.path.join(out_dir, "hardening"))
    shutil.rmtree(WORK, ignore_errors=True)
    os.makedirs(WORK)
    TMP = os.path.join(WORK, "tmp")
    os.makedirs(TMP)
    for part in (non_regular_inputs, outputs_never_clobber_inputs, plots, signals, integers,
                 reports, names_and_physx_scale, deep_and_long_robots):
        part()
    if failures:
        print("\n".join(failures))
        sys.exit(1)
    print("hardening: all checks passed")


if __name__ == "__main__":
    main()
