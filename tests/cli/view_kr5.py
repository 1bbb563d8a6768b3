#!/usr/bin/python3
"""A real robot with meshes: DART's KUKA KR5 (dart-doc's URDF and its 7 STL meshes) through
fd.view (a Simulation and its UrdfRobot) in headless Chromium with the network off: the page
reports the 7 meshes the URDF names as drawn and no inertia box (every link with mass has a
visual, or has a link merged into it that has), a fair share of the 3D view is not background,
the page asks nothing of the network and logs no console error. Skipped (exit 77) where Chromium
or dart-doc is not installed.

usage: view_kr5.py OUT_DIR PYTHON_DIR
"""
import os
import sys
import xml.etree.ElementTree as ElementTree

import numpy as np

from view_browser import SKIP, Browser, chromium_or_skip

KR5 = "/usr/share/doc/dart/data/urdf/KR5/KR5 sixx R650.urdf"


def fail(message):
    sys.exit(f"FAIL: {message}")


def main():
    out_dir, python_dir = sys.argv[1:3]
    chromium_or_skip()
    if not os.path.exists(KR5):
        print(f"SKIP: {KR5} is missing (apt-get install -y dart-doc)")
        sys.exit(SKIP)
    sys.path.insert(0, python_dir)
    import featherdrive as fd
    os.makedirs(out_dir, exist_ok=True)
    meshes = {m.get("filename") for m in ElementTree.parse(KR5).getroot()
              .findall("./link/visual/geometry/mesh")}
    robot = fd.load_urdf(KR5)
    sim = fd.Simulation(robot.model)
    q = np.array(sim.q)
    q[:] = 0.4  # a pose away from the zero one
    sim.set_q(q)
    page = fd.view(sim, os.path.join(out_dir, "view_kr5.html"), robot=robot, steps=5)
    if page.warnings:
        fail(f"warnings: {page.warnings}")
    if "<iframe srcdoc=" not in page._repr_html_():
        fail("_repr_html_ is not an iframe")

    browser = Browser(800, 900)
    try:
        browser.open(page.path)
        counts = browser.evaluate("[featherdrive.meshCount, featherdrive.boxCount]")
        print(f"{len(meshes)} meshes in the URDF; the page drew {counts[0]} meshes and "
              f"{counts[1]} inertia boxes")
        if counts != [len(meshes), 0] or len(meshes) != 7:
            fail(f"meshes and boxes drawn: {counts}")
        image = browser.screenshot()
        left, top, width, height = [int(v) for v in browser.evaluate("featherdrive.viewport")]
        view = image[top:top + height, left:left + width].astype(int)
        # Background: white, and the grid's light greys.
        ink = np.any(view < 180, axis=2).mean()
        print(f"{100 * ink:.1f}% of the view is robot (darker than the background and grid)")
        if ink < 0.02:
            fail("the robot is not drawn")
        problem = browser.offline_problem()
        if problem:
            fail(problem)
    finally:
        browser.close()


if __name__ == "__main__":
    main()
