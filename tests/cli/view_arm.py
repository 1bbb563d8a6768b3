#!/usr/bin/python3
"""`featherdrive view` on the arm demo (examples/arm7_pgs.yaml, 60 steps) in headless Chromium with
the network off (tests/cli/view_browser.py): the page loads from a file URL with no console error
and no request other than file:/data:/blob:; at three times set through the page's timeline
slider, the magenta marker at the tcp (a link merged into link7 through two fixed joints) lies
within a few pixels of where the page's camera matrices put the tcp's pose computed here
(fd.link_pose of link7 at the CSV's q of `featherdrive simulate`, then the URDF's fixed joint
origins); two screenshots differ around the arm and not in the view's corner; the curves' time
cursor moves linearly with the timeline; a joint sphere's pixel is the colour of the CSV's
|force| / the scene's max_force; the frames checkbox draws the joint frames; play advances the
timeline and pause stops it; --serve serves the page until SIGINT (exit 0). The same browser
then opens the pages of tests/cli/view_contacts.py (contacts, shapes, the KR5's meshes): one
Chromium with WebGL for all (starting one costs more than a page). Skipped (exit 77) where
Chromium is not installed; where dart-doc is not, after every other check has passed.

usage: view_arm.py FEATHERDRIVE SOURCE_DIR OUT_DIR PYTHON_DIR
"""
import csv
import os
import signal
import subprocess
import sys
import urllib.request
import xml.etree.ElementTree as ElementTree

import numpy as np

import view_contacts
from view_browser import SKIP, Browser, chromium_or_skip, pixels_of, project

STEPS = 60
MARKER = (255, 0, 255)
CURSOR = (0, 255, 255)


def fail(message):
    sys.exit(f"FAIL: {message}")


def rotation_rpy(r, p, y):
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def tcp_in_link7(urdf):
    """The tcp's origin in link7's frame: the fixed joints hand_joint and tcp_joint composed."""
    root = ElementTree.parse(urdf).getroot()
    origins = {}
    for joint in root.iter("joint"):
        o = joint.find("origin")
        origins[joint.get("name")] = (np.array([float(v) for v in o.get("xyz").split()]),
                                      rotation_rpy(*[float(v) for v in
                                                     (o.get("rpy") or "0 0 0").split()]))
    p_hand, r_hand = origins["hand_joint"]
    p_tcp, _ = origins["tcp_joint"]
    return p_hand + r_hand @ p_tcp


def srgb(c):
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


def check_joint_colours(image, frame, state, rows, limits, model, fd, tcp_at):
    """At the joint whose sphere is farthest on screen from the other spheres and the tcp, the
    pixel at its projected centre has the colour of its |force| / max_force."""
    q = np.array([float(rows[frame][f"q:joint{j}"]) for j in range(1, 8)])
    places = [project(fd.link_pose(model, q, f"link{j}")[1], state["view"], state["projection"],
                      state["viewport"]) for j in range(1, 8)]
    tcp = project(tcp_at(frame), state["view"], state["projection"], state["viewport"])
    clearance = [min(np.hypot(p[0] - o[0], p[1] - o[1]) for o in places[:j] + places[j + 1:]
                     + [tcp]) for j, p in enumerate(places)]
    j = int(np.argmax(clearance))
    if clearance[j] < 20:
        fail(f"frame {frame}: no joint sphere stands clear of the others ({clearance[j]:.0f} px)")
    ratio = min(1.0, abs(float(rows[frame][f"f:joint{j + 1}"])) / limits[j])
    expected = 255 * np.array([srgb(ratio), srgb(0.67 * (1 - ratio)), 0.0])
    x, y = (int(round(v)) for v in places[j])
    seen = image[y, x].astype(float)
    print(f"frame {frame}: joint{j + 1} sphere {seen.astype(int).tolist()} at |f| / max_force "
          f"{ratio:.3f}, expected {expected.round().astype(int).tolist()}")
    if np.abs(seen - expected).max() > 3:
        fail(f"frame {frame}: joint{j + 1}'s colour is not its |force| / max_force")


def main():
    cli, source, out_dir, python_dir = sys.argv[1:5]
    chromium_or_skip()
    sys.path.insert(0, python_dir)
    import featherdrive as fd
    os.makedirs(out_dir, exist_ok=True)
    scene = os.path.join(source, "examples", "arm7_pgs.yaml")
    run_csv = os.path.join(out_dir, "view_arm.csv")
    page = os.path.join(out_dir, "view_arm.html")
    sim = subprocess.run([cli, "simulate", scene, "--steps", str(STEPS), "--out", run_csv],
                         capture_output=True, text=True, timeout=120)
    if sim.returncode != 0:
        fail(f"simulate: exit {sim.returncode}: {sim.stderr}")
    run = subprocess.run([cli, "view", scene, "--csv", run_csv, "--out", page, "--marker", "tcp"],
                         capture_output=True, text=True, timeout=120)
    if run.returncode != 0:
        fail(f"view: exit {run.returncode}: {run.stderr}")
    if f"{STEPS + 1} frames" not in run.stdout or page not in run.stdout:
        fail(f"view's summary: {run.stdout!r}")

    # Where the tcp is, from featherdrive's kinematics at the CSV's q.
    loaded = fd.load_scene(scene)
    model = loaded.model
    limits = [next(d.drive.max_force for d in loaded.drives if d.joint == f"joint{j}")
              for j in range(1, 8)]
    with open(run_csv, newline="") as f:
        rows = list(csv.DictReader(f))
    tcp_offset = tcp_in_link7(os.path.join(source, "examples", "arm7.urdf"))

    def tcp_at(frame):
        q = np.array([float(rows[frame][f"q:joint{j}"]) for j in range(1, 8)])
        rotation, position = fd.link_pose(model, q, "link7")
        return position + rotation @ tcp_offset
    # The frame of the first two thirds where the tcp is farthest from its start (not the last
    # frame: the cursor's check needs a frame between the ends).
    moved = [np.linalg.norm(tcp_at(k) - tcp_at(0)) for k in range(2 * STEPS // 3)]
    later = int(np.argmax(moved))
    if moved[later] < 0.1:
        fail(f"the tcp moves only {moved[later]:.3f} m in the run: no test of motion")

    browser = Browser(1000, 1400)
    try:
        browser.open(page)
        shots, cursors = {}, {}
        for frame in (0, later, STEPS):
            browser.evaluate(f"(() => {{ const s = document.getElementById('fd-time'); "
                             f"s.value = '{frame}'; s.dispatchEvent(new Event('input')); }})()")
            if browser.evaluate("featherdrive.frame") != frame:
                fail(f"the slider set frame {browser.evaluate('featherdrive.frame')}, not {frame}")
            shots[frame] = browser.screenshot()
            state = browser.evaluate("({view: featherdrive.view, projection: "
                                     "featherdrive.projection, viewport: featherdrive.viewport, "
                                     "curves: document.getElementById('fd-curves')"
                                     ".getBoundingClientRect().top})")
            left, top, width, height = state["viewport"]
            image = shots[frame]
            # The marker, within the 3D view.
            xs, ys = pixels_of(image[int(top):int(top + height), int(left):int(left + width)],
                               MARKER)
            if len(xs) < 10:
                fail(f"frame {frame}: no magenta marker in the view ({len(xs)} pixels)")
            seen = np.array([xs.mean() + left, ys.mean() + top]) + 0.5  # pixel centres
            expected = np.array(project(tcp_at(frame), state["view"], state["projection"],
                                        state["viewport"]))
            error = np.linalg.norm(seen - expected)
            print(f"frame {frame}: tcp marker at ({seen[0]:.1f}, {seen[1]:.1f}) px, projected "
                  f"({expected[0]:.1f}, {expected[1]:.1f}): {error:.2f} px apart")
            if error > 3.0:
                fail(f"frame {frame}: the marker is {error:.1f} px from the tcp's projection")
            # The cursor of the first column of curves.
            curves_top = int(state["curves"])
            xs, _ = pixels_of(image[curves_top:, : image.shape[1] // 2], CURSOR, tolerance=2)
            if len(xs) < 50:
                fail(f"frame {frame}: no time cursor in the curves ({len(xs)} pixels)")
            cursors[frame] = xs.mean()
        span = cursors[STEPS] - cursors[0]
        predicted = cursors[0] + span * later / STEPS
        print(f"cursor x: {cursors[0]:.1f} px at frame 0, {cursors[later]:.1f} at frame {later} "
              f"(linear: {predicted:.1f}), {cursors[STEPS]:.1f} at frame {STEPS}")
        if span < 200 or abs(cursors[later] - predicted) > 2.0:
            fail("the curves' cursor does not follow the timeline")

        # The arm moved: the screenshots differ around the tcp's two places, not in the corner.
        left, top, width, height = [int(v) for v in state["viewport"]]
        a, b = (shots[k][top:top + height, left:left + width].astype(int) for k in (0, later))
        changed = np.any(np.abs(a - b) > 16, axis=2)
        corner = changed[:40, :40].sum()
        print(f"frames 0 and {later}: {changed.sum()} pixels of the view differ, "
              f"{corner} in its top-left corner")
        if corner != 0 or changed.sum() < 500:
            fail("the screenshots at two times do not differ where the arm moved")
        for frame in (0, later):
            x, y = project(tcp_at(frame), state["view"], state["projection"], state["viewport"])
            x, y = int(x) - left, int(y) - top
            if not changed[max(y - 15, 0):y + 15, max(x - 15, 0):x + 15].any():
                fail(f"nothing changed near the tcp's place at frame {frame}")
        # The joint spheres' colour: |force| / max_force (the CSV's f, the scene's max_force) as
        # linear RGB (r, 0.67 (1 - r), 0), which three.js writes sRGB-encoded.
        for frame in (later, STEPS):
            check_joint_colours(shots[frame], frame, state, rows, limits, model, fd, tcp_at)
        # Joint frames and axes on demand: drawn at frame STEPS once the box is checked.
        browser.evaluate("(() => { const b = document.getElementById('fd-frames'); b.checked = "
                         "true; b.dispatchEvent(new Event('change')); })()")
        framed = browser.screenshot()[top:top + height, left:left + width].astype(int)
        plain = shots[STEPS][top:top + height, left:left + width].astype(int)
        drawn = np.any(np.abs(framed - plain) > 16, axis=2)
        print(f"joint frames and axes: {drawn.sum()} pixels drawn, {drawn[:40, :40].sum()} in "
              "the corner")
        if drawn.sum() < 100 or drawn[:40, :40].any():
            fail("the joint frames and axes checkbox draws nothing")
        # Play from frame 0 until the page has moved on, then pause: the frame stays.
        browser.evaluate("featherdrive.setFrame(0); document.getElementById('fd-play').click()")
        played = browser.evaluate("new Promise(r => { const t0 = performance.now(); (function "
                                  "wait() { if (featherdrive.frame > 0 || performance.now() - t0 "
                                  "> 20000) r(featherdrive.frame); else requestAnimationFrame("
                                  "wait); })(); })")
        label = browser.evaluate("document.getElementById('fd-play').textContent")
        browser.evaluate("document.getElementById('fd-play').click()")
        paused = browser.evaluate("[featherdrive.playing, featherdrive.frame]")
        after = browser.evaluate("new Promise(r => setTimeout(() => r(featherdrive.frame), 300))")
        print(f"play: frame {played} ({label!r} shown), paused at {paused[1]}, then {after}")
        if played < 1 or label != "pause" or paused[0] or after != paused[1]:
            fail("play/pause does not run and stop the timeline")
        problem = browser.offline_problem()
        if problem:
            fail(problem)
        print(f"no console error; {len(browser.requests)} requests, all file:/data:/blob:")
        kr5 = view_contacts.pages(browser, cli, source, out_dir)
    finally:
        browser.close()

    # A browser without WebGL (--disable-3d-apis, as some headless and remote ones; with no GPU
    # process either, which would start SwiftShader for nothing): the page says so in one line
    # and keeps the timeline and the curves, with no console error.
    browser = Browser(1000, 1400, extra_args=["--disable-3d-apis", "--disable-gpu"])
    try:
        browser.open(page)
        note = browser.evaluate("(() => { const n = document.getElementById('fd-no-webgl'); "
                                "return n ? n.textContent : null; })()")
        if browser.evaluate("featherdrive.webgl") is not False or not note or "3D view" not in note:
            fail(f"without WebGL: no line saying the 3D view is unavailable ({note!r})")
        browser.evaluate(f"(() => {{ const s = document.getElementById('fd-time'); "
                         f"s.value = '{later}'; s.dispatchEvent(new Event('input')); }})()")
        image = browser.screenshot()
        curves_top = int(browser.evaluate(
            "document.getElementById('fd-curves').getBoundingClientRect().top"))
        xs, _ = pixels_of(image[curves_top:, : image.shape[1] // 2], CURSOR, tolerance=2)
        expected = cursors[0] + span * later / STEPS  # where the page with WebGL drew it
        if browser.evaluate("featherdrive.frame") != later or len(xs) < 50 or \
                abs(xs.mean() - expected) > 2.0:
            fail(f"without WebGL: the timeline or the curves' cursor do not work "
                 f"({len(xs)} cursor pixels)")
        drawn = np.any(image[curves_top:] < 200, axis=2).sum()
        if drawn < 1000:
            fail(f"without WebGL: the curves are not drawn ({drawn} dark pixels)")
        problem = browser.offline_problem()
        if problem:
            fail(f"without WebGL: {problem}")
        print(f"without WebGL: {note!r}; curves drawn ({drawn} dark pixels), cursor at "
              f"{xs.mean():.1f} px")
    finally:
        browser.close()

    # --serve: the page over HTTP on 127.0.0.1 until SIGINT, then exit 0.
    server = subprocess.Popen([cli, "view", scene, "--csv", run_csv, "--out", page, "--serve",
                               "--port", "0"], stdout=subprocess.PIPE, text=True)
    try:
        line = ""
        while "serving" not in line:
            line = server.stdout.readline()
            if not line:
                fail(f"--serve said no address (exit {server.wait()})")
        url = line.split()[1]
        with urllib.request.urlopen(url, timeout=30) as reply:
            served = reply.read()
        with open(page, "rb") as f:
            if served != f.read():
                fail(f"{url} is not the page")
        print(f"--serve: {url} serves the page")
    finally:
        server.send_signal(signal.SIGINT)
        code = server.wait(timeout=30)
    if code != 0:
        fail(f"--serve ended with exit {code} after SIGINT")
    if not kr5:
        sys.exit(SKIP)


if __name__ == "__main__":
    main()
