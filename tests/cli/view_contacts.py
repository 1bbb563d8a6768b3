#!/usr/bin/python3
"""`featherdrive view` of the quadruped standing on the ground (tests/data/quadruped_ground.yaml,
40 steps) in headless Chromium with the network off: the page's data carries, per frame, one
contact arrow per shin (the legs touch the ground with their shins only), each the CSV's contact
columns of `featherdrive simulate` for that link and starting at or above the ground; at the last
frame the page shows 4 arrows (featherdrive.contactArrows), at frame 0 none (no step has run), and
none once the "contact forces" box is unchecked; a page of the same run read back from the CSV
(--csv) shows the same 4 arrows; the arrows are drawn (the view changes near the feet). Then the
Ant walking (examples/ant_walk.yaml, an MJCF robot without visuals, 20 steps): the page draws one
shape per geom of the Ant's bodies in examples/ant.xml (counted here from the file: a sphere and
12 capsules) and no inertia box, and draws the ground (featherdrive.ground; its plane covers the
bottom of the view, which is white without it). Last, one link with a shape of every type
(tests/data/every_shape.xml, a convex hull among them) over a tilted ground: one of each drawn,
the page's ground plane the scene's. Then a real robot with meshes, DART's KUKA KR5 (dart-doc's
URDF and its 7 STL meshes) through fd.view (a Simulation and its UrdfRobot): the page reports the
7 meshes the URDF names as drawn and no inertia box (every link with mass has a visual, or has a
link merged into it that has), and a fair share of the 3D view is not background. One browser
opens the five pages (ctest's cli.view: tests/cli/view_arm.py's, after the arm's page); none asks
anything of the network or logs a console error. Skipped (exit 77) where Chromium is not
installed; where dart-doc is not, the KR5 is left out and the test exits 77 once the other pages
have passed.

usage: view_contacts.py FEATHERDRIVE SOURCE_DIR OUT_DIR PYTHON_DIR
"""
import csv
import json
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

import numpy as np

from view_browser import SKIP, Browser, chromium_or_skip

STEPS = 40
LEGS = ("fl", "fr", "hl", "hr")
KR5 = "/usr/share/doc/dart/data/urdf/KR5/KR5 sixx R650.urdf"


def fail(message):
    sys.exit(f"FAIL: {message}")


def run(args):
    done = subprocess.run(args, capture_output=True, text=True, timeout=120)
    if done.returncode != 0:
        fail(f"{' '.join(args[1:3])}: exit {done.returncode}: {done.stderr}")
    return done


def page_data(page):
    with open(page, encoding="utf-8") as f:
        text = f.read()
    found = re.search(r'<script type="application/json" id="fd-data">(.*?)</script>', text, re.S)
    return json.loads(found.group(1))


def no_network_nor_error(browser):
    problem = browser.offline_problem()
    if problem:
        fail(problem)


def set_frame(browser, frame):
    browser.evaluate(f"(() => {{ const s = document.getElementById('fd-time'); "
                     f"s.value = '{frame}'; s.dispatchEvent(new Event('input')); }})()")
    return browser.evaluate("featherdrive.contactArrows")


def main():
    cli, source, out_dir, python_dir = sys.argv[1:5]
    chromium_or_skip()
    sys.path.insert(0, python_dir)
    os.makedirs(out_dir, exist_ok=True)
    browser = Browser(1000, 1200)
    try:
        kr5 = pages(browser, cli, source, out_dir)
    finally:
        browser.close()
    if not kr5:
        sys.exit(SKIP)


def pages(browser, cli, source, out_dir):
    """The five pages in `browser` (tests/cli/view_arm.py passes its own: starting Chromium costs
    more than a page; the console errors and requests it records are every page's so far).
    False where dart-doc is missing: the KR5's page is left out, the others checked."""
    scene = os.path.join(source, "tests", "data", "quadruped_ground.yaml")
    run_csv = os.path.join(out_dir, "view_contacts.csv")
    page = os.path.join(out_dir, "view_contacts.html")
    csv_page = os.path.join(out_dir, "view_contacts_csv.html")
    run([cli, "simulate", scene, "--steps", str(STEPS), "--out", run_csv])
    run([cli, "view", scene, "--steps", str(STEPS), "--out", page])
    run([cli, "view", scene, "--csv", run_csv, "--out", csv_page])
    with open(run_csv, newline="") as f:
        rows = list(csv.DictReader(f))

    # The page's arrows are the CSV's contact forces, per shin, from points on the ground.
    data = page_data(page)
    contacts = data["contacts"]
    mass = 4.0 + 4 * (0.5 + 0.3)  # tests/data/quadruped.urdf
    if abs(contacts["per_newton"] * mass * 9.81 - 1.0) > 1e-12:
        fail(f"scale {contacts['per_newton']} m/N is not 1 m per the robot's weight")
    frames = contacts["frames"]
    if len(frames) != STEPS + 1 or frames[0]:
        fail(f"{len(frames)} frames of arrows, the first {frames[0]}")
    for k in (1, STEPS):
        arrows = np.array(frames[k]).reshape(-1, 7)
        names = sorted(data["links"][int(i)] for i in arrows[:, 0])
        if names != sorted(f"{leg}_shin" for leg in LEGS):
            fail(f"frame {k}: arrows on {names}")
        for a in arrows:
            name = data["links"][int(a[0])]
            expected = [float(rows[k][f"contact:{name}:{c}"]) for c in ("fx", "fy", "fz")]
            if np.abs(a[4:] - expected).max() > 1e-5 or not -0.03 < a[3] < 0.03:
                fail(f"frame {k}: {name}'s arrow {a.tolist()}, the CSV's force {expected}")
    print(f"the page's arrows are the CSV's forces at the shins' contact points "
          f"(frame {STEPS}: total fz {np.array(frames[STEPS]).reshape(-1, 7)[:, 6].sum():.4f} N)")

    browser.resize(1000, 1200)
    browser.open(page)
    counts = [set_frame(browser, 0)]
    left, top, width, height = [int(v) for v in browser.evaluate("featherdrive.viewport")]
    counts.append(set_frame(browser, STEPS))
    browser.evaluate("(() => { const b = document.getElementById('fd-contacts'); b.checked = "
                     "false; b.dispatchEvent(new Event('change')); })()")
    counts.append(browser.evaluate("featherdrive.contactArrows"))
    hidden = browser.screenshot()[top:top + height, left:left + width].astype(int)
    browser.evaluate("(() => { const b = document.getElementById('fd-contacts'); b.checked = "
                     "true; b.dispatchEvent(new Event('change')); })()")
    counts.append(browser.evaluate("featherdrive.contactArrows"))
    drawn = np.any(np.abs(browser.screenshot()[top:top + height, left:left + width]
                          .astype(int) - hidden) > 16, axis=2).sum()
    print(f"arrows at frame 0, frame {STEPS}, unchecked, checked again: {counts}; "
          f"{drawn} pixels drawn by them")
    if counts != [0, 4, 0, 4]:
        fail(f"the page's arrow counts are {counts}, expected [0, 4, 0, 4]")
    if browser.evaluate("featherdrive.webgl") and drawn < 50:
        fail("the arrows draw nothing")
    no_network_nor_error(browser)

    browser.open(csv_page)
    from_csv = set_frame(browser, STEPS)
    print(f"from the CSV: {from_csv} arrows at frame {STEPS}")
    if from_csv != 4:
        fail(f"the page of the CSV shows {from_csv} arrows")
    no_network_nor_error(browser)
    ant_page(browser, cli, source, out_dir)
    every_shape_page(browser, cli, source, out_dir)
    if not os.path.exists(KR5):
        print(f"SKIP: the KR5's page: {KR5} is missing (apt-get install -y dart-doc); "
              "the other pages passed")
        return False
    kr5_page(browser, out_dir)
    return True


def body_geoms(mjcf):
    """The count of each shape type among the geoms of an MJCF file's bodies (the world's own,
    such as a floor, are not a link's; a mesh is drawn as its convex hull)."""
    root = ElementTree.parse(mjcf).getroot()
    counts = {}
    for geom in (g for body in root.iter("body") for g in body.findall("geom")):
        kind = geom.get("type", "sphere").replace("mesh", "convex")
        counts[kind] = counts.get(kind, 0) + 1
    return counts


def every_shape_page(browser, cli, source, out_dir):
    """One shape of each type (tests/data/every_shape.xml) drawn over a tilted ground."""
    page = os.path.join(out_dir, "view_every_shape.html")
    run([cli, "view", os.path.join(source, "tests", "data", "every_shape.yaml"), "--out", page])
    expected = body_geoms(os.path.join(source, "tests", "data", "every_shape.xml"))
    normal = np.array([0.1, 0, 1]) / np.linalg.norm([0.1, 0, 1])  # every_shape.yaml's ground
    ground = page_data(page)["ground"]
    if np.abs(np.array(ground["normal"]) - normal).max() > 1e-12 or ground["height"] != -0.1:
        fail(f"the page's ground {ground}, every_shape.yaml's normal {normal.tolist()}, -0.1")
    browser.resize(1000, 900)
    browser.open(page)
    drawn = browser.evaluate("[featherdrive.shapeTypes, featherdrive.boxCount, "
                             "featherdrive.ground]")
    print(f"every shape type: {drawn[0]} (every_shape.xml: {expected}), {drawn[1]} boxes, "
          f"ground {drawn[2]}")
    if len(expected) != 6 or drawn != [expected, 0, True]:
        fail(f"the page draws {drawn}, every_shape.xml has {expected}")
    no_network_nor_error(browser)


def ant_page(browser, cli, source, out_dir):
    """The Ant's shapes and the ground in the page of examples/ant_walk.yaml."""
    page = os.path.join(out_dir, "view_ant.html")
    run([cli, "view", os.path.join(source, "examples", "ant_walk.yaml"), "--steps", "20",
         "--out", page])
    expected = body_geoms(os.path.join(source, "examples", "ant.xml"))
    browser.open(page)
    browser.evaluate("featherdrive.setFrame(20)")
    drawn = browser.evaluate("[featherdrive.shapeCount, featherdrive.shapeTypes, "
                             "featherdrive.boxCount, featherdrive.ground]")
    left, top, width, height = [int(v) for v in browser.evaluate("featherdrive.viewport")]
    bottom = browser.screenshot()[top + 3 * height // 4:top + height, left:left + width]
    white = np.all(bottom >= 250, axis=2).mean()
    print(f"the Ant: {drawn[0]} shapes {drawn[1]} (ant.xml: {expected}), {drawn[2]} "
          f"boxes, ground {drawn[3]}; {white:.1%} of the view's bottom quarter white")
    if expected != {"sphere": 1, "capsule": 12}:  # the parse above found the Ant's geoms
        fail(f"ant.xml's bodies have the geoms {expected}")
    if drawn[:3] != [sum(expected.values()), expected, 0]:
        fail(f"the page draws {drawn[:3]}, ant.xml has {expected} (and no box)")
    if drawn[3] is not True:
        fail("the page draws no ground")
    if browser.evaluate("featherdrive.webgl") and white > 0.2:
        fail(f"{white:.1%} of the view's bottom quarter is white: the ground is not drawn")
    no_network_nor_error(browser)



def kr5_page(browser, out_dir):
    """DART's KR5 through fd.view: its 7 meshes drawn, no inertia box, the robot in the view."""
    import featherdrive as fd
    meshes = {m.get("filename") for m in ElementTree.parse(KR5).getroot()
              .findall("./link/visual/geometry/mesh")}
    robot = fd.load_urdf(KR5)
    sim = fd.Simulation(robot.model)
    q = np.array(sim.q)
    q[:] = 0.4  # a pose away from the zero one
    sim.set_q(q)
    page = fd.view(sim, os.path.join(out_dir, "view_kr5.html"), robot=robot, steps=5)
    if page.warnings:
        fail(f"KR5: warnings: {page.warnings}")
    if "<iframe srcdoc=" not in page._repr_html_():
        fail("KR5: _repr_html_ is not an iframe")
    browser.resize(800, 900)
    browser.open(page.path)
    counts = browser.evaluate("[featherdrive.meshCount, featherdrive.boxCount]")
    print(f"KR5: {len(meshes)} meshes in the URDF; the page drew {counts[0]} meshes and "
          f"{counts[1]} inertia boxes")
    if counts != [len(meshes), 0] or len(meshes) != 7:
        fail(f"KR5: meshes and boxes drawn: {counts}")
    image = browser.screenshot()
    left, top, width, height = [int(v) for v in browser.evaluate("featherdrive.viewport")]
    view = image[top:top + height, left:left + width].astype(int)
    # Background: white, and the grid's light greys.
    ink = np.any(view < 180, axis=2).mean()
    print(f"KR5: {100 * ink:.1f}% of the view is robot (darker than the background and grid)")
    if ink < 0.02:
        fail("KR5: the robot is not drawn")
    no_network_nor_error(browser)


if __name__ == "__main__":
    main()
