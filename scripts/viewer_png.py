#!/usr/bin/python3
"""Makes docs/viewer.png: `featherdrive view` of a contact scene (the quadruped standing on the
ground, tests/data/quadruped_ground.yaml, its shins' contact forces drawn as arrows) at its last
frame, in Debian's headless Chromium (the viewer tests' tests/cli/view_browser.py), the page's 3D
view cropped out.

usage: scripts/viewer_png.py [FEATHERDRIVE [SCENE [STEPS [OUT]]]]
"""
import base64
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "cli"))

from view_browser import Browser  # noqa: E402


def main():
    args = sys.argv[1:] + [None] * 4
    cli = args[0] or os.path.join(ROOT, "build", "tools", "featherdrive")
    scene = args[1] or os.path.join(ROOT, "tests", "data", "quadruped_ground.yaml")
    steps = args[2] or "40"
    out = args[3] or os.path.join(ROOT, "docs", "viewer.png")
    page = os.path.join(tempfile.mkdtemp(prefix="fd-viewer-png-"), "view.html")
    subprocess.run([cli, "view", scene, "--steps", steps, "--out", page], check=True)
    browser = Browser(900, 800)
    try:
        browser.open(page)
        browser.evaluate(f"(() => {{ const s = document.getElementById('fd-time'); "
                         f"s.value = '{steps}'; s.dispatchEvent(new Event('input')); }})()")
        arrows = browser.evaluate("featherdrive.contactArrows")
        left, top, width, height = [int(v) for v in browser.evaluate("featherdrive.viewport")]
        browser.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
        shot = browser.call("Page.captureScreenshot", session=True, format="png",
                            clip={"x": left, "y": top, "width": width, "height": height,
                                  "scale": 1})
        with open(out, "wb") as f:
            f.write(base64.b64decode(shot["data"]))
        print(f"{out}: {width} x {height}, frame {steps}, {arrows} contact arrows")
    finally:
        browser.close()


if __name__ == "__main__":
    main()
