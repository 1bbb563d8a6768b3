"""The 3D viewer page (docs/viewer.md): `featherdrive view SCENE [--csv RUN.csv]` and fd.view.

One self-contained HTML file plays a run on the robot: the URDF's visuals (meshes inlined), links
without visuals as their collision shapes, else as their equivalent-inertia boxes, every link
posed at every frame by the world poses featherdrive computes (fd.link_world_poses), the ground
plane and its force on each link as arrows (with a ground), a timeline and per-joint curves of
q, target and drive force. The page's JavaScript (viewer/src/page.js with three.js and
urdf-loader) is bundled at build time into build/viewer/viewer.js and inlined here, so the page
needs no network.
"""
import argparse
import base64
import functools
import html
import http.server
import json
import math
import os
import pathlib
import sys
import warnings
import xml.etree.ElementTree as ElementTree

import numpy as np

import featherdrive_common as common


# The most steps of a run the page shows (each a frame of every link's pose).
MAX_STEPS = 1_000_000


class ViewerUnavailable(RuntimeError):
    """The bundled page script is missing (node and npm were not there at build time)."""


def bundle_path():
    """Where the build put the page's script: $FEATHERDRIVE_VIEWER_BUNDLE, else
    build/viewer/viewer.js beside this module's build/python."""
    env = os.environ.get("FEATHERDRIVE_VIEWER_BUNDLE")
    if env:
        return pathlib.Path(env)
    return pathlib.Path(__file__).resolve().parent.parent / "viewer" / "viewer.js"


def _read_bundle():
    path = bundle_path()
    if path.is_file():
        return path.read_text(encoding="utf-8")
    import shutil
    if shutil.which("node") is None or shutil.which("npm") is None:
        raise ViewerUnavailable(
            "the viewer needs node and npm to bundle its page at build time: "
            "apt-get install -y nodejs npm, then build again")
    raise ViewerUnavailable(f"the viewer's script {path} is missing: build it (cmake --build "
                            "build --target featherdrive_viewer; configure again first if node "
                            "came after the build was configured)")


class ViewerPage:
    """A written page: .path, .html (its text), .warnings; shown inline in Jupyter (an iframe)."""

    def __init__(self, path, text, frames, notes):
        self.path = pathlib.Path(path)
        self.html = text
        self.frames = frames
        self.warnings = list(notes)

    def __fspath__(self):
        return str(self.path)

    def __repr__(self):
        return f"ViewerPage({str(self.path)!r})"

    def _repr_html_(self):
        return (f'<iframe srcdoc="{html.escape(self.html, quote=True)}" '
                'style="width: 100%; height: 820px; border: 0"></iframe>')


# ---- the run: times, q rows and per-joint series ----------------------------------------------

class _Run:
    def __init__(self, model, times, q, forces=None, targets=None, max_force=None,
                 contacts=None, ground=None):
        self.model = model
        self.times = np.asarray(times, dtype=float)
        self.q = np.asarray(q, dtype=float)
        self.forces = forces    # (T, nv) or None
        self.targets = targets  # {dof: (T,) array}
        self.max_force = max_force or {}  # {dof: finite limit}
        # Per row, the contact arrows [(link, origin (3,) or None: the link's origin, force (3,))]
        # of the step that reached it; None without a ground.
        self.contacts = contacts
        self.ground = ground if ground is not None and ground.enabled else None  # fd.Ground


def _contact_arrows(sim):
    """The arrows of sim's last step: each link the ground pushed, from the average of its
    contact points, along its force (world axes, N)."""
    points = {}
    for c in sim.contacts():
        points.setdefault(c.link, []).append(np.asarray(c.position, dtype=float))
    forces = np.asarray(sim.link_contact_force())
    return [(link, np.mean(p, axis=0), forces[link]) for link, p in sorted(points.items())
            if np.any(forces[link])]


def _drive_limit(fd, sim, dof):
    """The drive's or explicit actuator's force limit on the dof, None when unlimited."""
    drive = sim.drive(dof)
    if drive.type != fd.DriveType.none:
        return drive.max_force if math.isfinite(drive.max_force) else None
    actuator = sim.actuator(dof)
    if actuator.kind != fd.ActuatorKind.none and math.isfinite(actuator.effort_limit):
        return actuator.effort_limit
    return None


def _scene_targets(fd, scene, rows):
    """Target position per driven dof at each row: row 0 the first step's targets (as
    make_simulation sets them), row k + 1 those apply_targets sets for step k."""
    sim = fd.make_simulation(scene)
    dofs = [spec.dof for spec in scene.drives]
    out = np.zeros((rows, len(dofs)))

    def read(row):  # apply_targets sets explicit actuators' targets there too
        for i, spec in enumerate(scene.drives):
            out[row, i] = sim.drive(spec.dof).target_position
    read(0)
    for k in range(rows - 1):
        fd.apply_targets(scene, sim, k)
        read(k + 1)
    limits = {d: _drive_limit(fd, sim, d) for d in dofs}
    return {d: out[:, i] for i, d in enumerate(dofs)}, {d: v for d, v in limits.items() if v}


def _run_scene(fd, scene, steps, notes):
    sim = fd.make_simulation(scene)
    nv = scene.model.nv
    q, f, t = [np.array(sim.q)], [np.zeros(nv)], [float(sim.time)]
    contacts = [[]] if sim.ground().enabled or sim.contact_options().self_collision else None
    for k in range(steps):
        fd.apply_targets(scene, sim, k)
        try:
            sim.step()
        except fd.DivergenceError as exc:
            notes.append(f"{scene.path}: the run diverged at step {k + 1} ({exc}); the page "
                         f"shows the {k + 1} states before")
            break
        q.append(np.array(sim.q))
        f.append(np.array(sim.drive_force) + np.array(sim.actuator_force))
        t.append(float(sim.time))
        if contacts is not None:
            contacts.append(_contact_arrows(sim))
    targets, limits = _scene_targets(fd, scene, len(q))
    return _Run(scene.model, t, q, np.array(f), targets, limits, contacts, sim.ground())


def _number(text, where):
    if not common.is_decimal(text):  # as the C++ readers: not 1_0, " 1" or "infinity"
        raise ValueError(f"{where}: {text!r} is not a number")
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{where}: {text} is not finite")
    return value


def _read_csv(fd, scene, path):
    """The run of a trajectory CSV (`featherdrive simulate --out`) of the scene's model: q from
    its q columns, forces from its f columns, targets from the scene."""
    rows = common.read_csv(path, "the CSV")
    model = scene.model
    robot = scene.robot
    if not rows:
        raise ValueError(f"{path}: empty (expected the header step,t,q:<joint>...)")
    header = rows[0]
    index = {name: i for i, name in enumerate(header)}
    links = model.links
    q_columns = []  # (column, q index) of a floating root's 7 entries
    if model.floating_base():
        root = links[0]
        for k, c in enumerate(("x", "y", "z", "qw", "qx", "qy", "qz")):
            q_columns.append((f"q:{root.joint_name}:{c}", root.q_index + k))
    # Each dof's position (fd.dof_positions: a spherical axis's PhysX position), set into q below.
    dofs = [d for d in robot.dof_order if fd.has_dof_position(model, d)]
    dof_columns = [(f"q:{model.dof_names[d]}", d) for d in dofs]
    for name in ["t"] + [c for c, _ in q_columns + dof_columns]:
        if name not in index:
            raise ValueError(f"{path}: no column '{name}' (the model of {scene.path} needs it)")
    f_columns = {d: index.get(f"f:{model.dof_names[d]}") for d in range(model.nv)}
    # contact:<link>:fx,fy,fz (with the ground on): the CSV has no contact points, so these
    # arrows start at the link's origin.
    contact_columns = [(i, [index[f"contact:{link.name}:{a}"] for a in ("fx", "fy", "fz")])
                       for i, link in enumerate(links)
                       if all(f"contact:{link.name}:{a}" in index for a in ("fx", "fy", "fz"))]
    contacts = [] if contact_columns else None
    body = rows[1:]
    if not body:
        raise ValueError(f"{path}: no rows after the header")
    times = np.zeros(len(body))
    q = np.tile(np.array(model.neutral_configuration()), (len(body), 1))
    positions = np.zeros((len(body), len(dofs)))
    forces = np.zeros((len(body), model.nv))
    for r, row in enumerate(body):
        if len(row) != len(header):
            raise ValueError(f"{path}: row {r + 1} has {len(row)} fields, the header "
                             f"{len(header)}")
        times[r] = _number(row[index["t"]], f"{path}: row {r + 1}, column t")
        if r and times[r] < times[r - 1]:
            raise ValueError(f"{path}: row {r + 1}, column t: {row[index['t']]} is earlier "
                             "than the row before")
        for column, qi in q_columns:
            q[r, qi] = _number(row[index[column]], f"{path}: row {r + 1}, column {column}")
        for j, (column, _) in enumerate(dof_columns):
            positions[r, j] = _number(row[index[column]], f"{path}: row {r + 1}, column {column}")
        for d, c in f_columns.items():
            if c is not None:
                forces[r, d] = _number(row[c], f"{path}: row {r + 1}, column {header[c]}")
        if contacts is not None:
            arrows = [(i, None, np.array([_number(row[c], f"{path}: row {r + 1}, column "
                                                  f"{header[c]}") for c in columns]))
                      for i, columns in contact_columns]
            contacts.append([a for a in arrows if np.any(a[2])])
    q = fd.set_dof_positions(model, q, dofs, positions)
    targets, limits = _scene_targets(fd, scene, len(body))
    return _Run(model, times, q, forces, targets, limits, contacts, scene.ground)


def _run_simulation(fd, sim, steps):
    """A copy of sim stepped `steps` times with its drives' targets as they are."""
    s = sim.copy()
    model = s.model
    driven = [d for d in range(model.nv) if s.drive(d).type != fd.DriveType.none]
    q, f, t = [np.array(s.q)], [np.zeros(model.nv)], [float(s.time)]
    contacts = [[]] if s.ground().enabled or s.contact_options().self_collision else None
    for _ in range(steps):
        s.step()
        q.append(np.array(s.q))
        f.append(np.array(s.drive_force) + np.array(s.actuator_force))
        t.append(float(s.time))
        if contacts is not None:
            contacts.append(_contact_arrows(s))
    targets = {d: np.full(len(q), s.drive(d).target_position) for d in driven}
    limits = {d: _drive_limit(fd, s, d) for d in driven}
    return _Run(model, t, q, np.array(f), targets, {d: v for d, v in limits.items() if v},
                contacts, s.ground())


# ---- geometry ---------------------------------------------------------------------------------

def _inertia_boxes(model):
    """The box of each link with mass: the same mass, centre of mass and rotational inertia (its
    sides along the principal axes; docs/viewer.md)."""
    boxes = {}
    for link in model.links:
        m = float(link.mass)
        if not m > 0:
            continue
        moments, axes = np.linalg.eigh(np.asarray(link.inertia_com, dtype=float).reshape(3, 3))
        if np.linalg.det(axes) < 0:
            axes[:, 2] = -axes[:, 2]
        total = moments.sum()
        # I_k = m (s_i^2 + s_j^2) / 12  =>  s_k^2 = 6 (I_i + I_j - I_k) / m
        sides = np.sqrt(np.maximum(6.0 * (total - 2.0 * moments) / m, 0.0))
        floor = max(sides.max() * 0.05, 1e-3)  # a flat or zero inertia still shows as a slab
        sides = np.maximum(sides, floor)
        boxes[link.name] = {"center": [float(c) for c in link.com],
                            "axes": [float(a) for a in axes.T.flatten()],
                            "size": [float(s) for s in sides]}
    return boxes


def _link_shapes(model):
    """Each link's collision shapes (drawn where the link has no visual): {link: [{type, size,
    position, axes (the shape's x, y, z in the link frame, one after the other), vertices
    (convex only, flat, in the shape frame)}]}; sizes as ShapeType says."""
    shapes = {}
    for shape in model.shapes:
        entry = {"type": str(shape.type.name), "size": [float(v) for v in shape.size],
                 "position": [float(v) for v in shape.position],
                 "axes": [float(a) for a in np.asarray(shape.rotation, dtype=float).T.flatten()]}
        if shape.type.name == "convex":
            vertices = np.asarray(shape.vertices, dtype=float)
            entry["vertices"] = np.round(vertices, 7).flatten().tolist()
        shapes.setdefault(model.links[shape.link].name, []).append(entry)
    return shapes


def _page_ground(ground):
    """The run's ground plane n . x = height as {normal (unit), height}, or None."""
    if ground is None:
        return None
    return {"normal": [float(v) for v in ground.normal], "height": float(ground.height)}


def _resolve_mesh(filename, urdf_dir, packages):
    """The file a mesh filename names, or (None, why)."""
    if filename.startswith("package://"):
        name, _, rest = filename[len("package://"):].partition("/")
        if name not in packages:
            return None, f"package '{name}' is not mapped (--package {name}=DIR)"
        return pathlib.Path(packages[name]) / rest, None
    if filename.startswith("file://"):
        return pathlib.Path(filename[len("file://"):]), None
    if "://" in filename:
        return None, "only package:// and file:// addresses are read"
    return urdf_dir / filename, None


def _urdf_geometry(urdf_path, packages):
    """The URDF's text and its visual meshes {filename: base64}, with warnings for the meshes
    that do not resolve (their links are drawn without them); no text for an MJCF file."""
    text = common.read_text(urdf_path, "the URDF")
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as exc:
        raise ValueError(f"{urdf_path}: cannot read its visuals: {exc}") from None
    meshes, notes, inputs = {}, [], []
    if root.tag != "robot":  # MJCF: drawn from the shapes and inertia boxes
        return None, meshes, notes, inputs
    for link in root.iter("link"):
        for mesh in link.findall("./visual/geometry/mesh"):
            filename = mesh.get("filename", "")
            if filename in meshes:
                continue
            path, why = _resolve_mesh(filename, pathlib.Path(urdf_path).parent, packages)
            if path is not None and not path.is_file():
                why = f"{path} not found"
            if why is None and path.suffix.lower() not in (".stl", ".dae"):
                why = "only STL and DAE meshes are drawn"
            data = None
            if why is None:
                try:
                    data = common.read_bytes(path, "the mesh")
                except ValueError as exc:
                    why = str(exc)
            if why is not None:
                notes.append(f"{urdf_path}: link '{link.get('name')}' mesh {filename}: {why}; "
                             "drawn without it")
                continue
            meshes[filename] = base64.b64encode(data).decode("ascii")
            inputs.append(path)
    return text, meshes, notes, inputs


# ---- the page ---------------------------------------------------------------------------------

def _page_data(fd, run, robot, urdf_text, meshes, title, marker):
    model = run.model
    names, poses = fd.link_world_poses(model, run.q, robot)
    merged_into = {n: m[0] for n, m in robot.merged.items()} if robot is not None else {}
    if marker is not None and marker not in names:
        raise ValueError(f"marker: no link '{marker}' (links: {', '.join(names)})")
    joints = []
    order = robot.dof_order if robot is not None else range(model.nv)
    dofs = [d for d in order if fd.has_dof_position(model, d)]
    positions = fd.dof_positions(model, np.asarray(run.q, dtype=float).reshape(-1, model.nq), dofs)
    for j, d in enumerate(dofs):
        link = model.links[model.dof_link[d]]
        # A spherical joint's axis k: the joint frame's x, y or z (twist, swing1, swing2).
        axis = np.eye(3)[d - link.v_index] if link.nv == 3 else link.axis
        joint = {"name": model.dof_names[d], "link": link.name,
                 "axis": [float(a) for a in axis],
                 "q": np.round(positions[:, j], 9).tolist(),
                 "target": None, "force": None, "max_force": run.max_force.get(d),
                 "largest_force": 0.0}
        if d in run.targets:
            joint["target"] = np.round(run.targets[d], 9).tolist()
            if run.forces is not None:
                joint["force"] = np.round(run.forces[:, d], 9).tolist()
                joint["largest_force"] = float(np.abs(run.forces[:, d]).max())
        joints.append(joint)
    return {
        "contacts": _page_contacts(run, names, poses),
        "title": title, "dt": float(run.times[1] - run.times[0]) if len(run.times) > 1 else 0.0,
        "times": np.round(run.times, 9).tolist(), "links": list(names),
        "poses": np.round(poses, 7).flatten().tolist(),
        "urdf": urdf_text, "meshes": meshes, "boxes": _inertia_boxes(model),
        "shapes": _link_shapes(model), "ground": _page_ground(run.ground),
        "merged_into": merged_into, "joints": joints, "marker": marker,
    }


def _page_contacts(run, names, poses):
    """The contact arrows of each frame, flat [link, x, y, z, fx, fy, fz, ...] (link: index into
    the page's links), and their scale in m/N: 1 m for the robot's weight m |g| (else for the
    run's largest force); None without a ground."""
    if run.contacts is None:
        return None
    model = run.model
    weight = sum(float(link.mass) for link in model.links) * float(np.linalg.norm(model.gravity))
    largest = max((float(np.linalg.norm(f)) for row in run.contacts for _, _, f in row),
                  default=0.0)
    per_newton = 1.0 / weight if weight > 0 else 1.0 / largest if largest > 0 else 0.0
    poses = np.asarray(poses).reshape(len(run.times), len(names), 7)
    frames = []
    for k, row in enumerate(run.contacts):
        flat = []
        for link, origin, force in row:
            i = names.index(model.links[link].name)
            at = poses[k, i, :3] if origin is None else origin
            flat += [i, *np.round(at, 7).tolist(), *np.round(force, 6).tolist()]
        frames.append(flat)
    return {"per_newton": per_newton, "frames": frames}


def _html(data, bundle):
    # A <script>'s text ends at "</script" and "<!--" changes how it is read: every "<" of the
    # JSON (all inside strings) becomes \u003c, and the bundle must hold neither.
    payload = json.dumps(data, allow_nan=False, separators=(",", ":")).replace("<", "\\u003c")
    lowered = bundle.lower()
    if "</script" in lowered or "<!--" in lowered:
        raise RuntimeError(f"{bundle_path()}: the viewer's script holds '</script' or '<!--'")
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
            f"<title>featherdrive view: {html.escape(data['title'])}</title></head>\n<body>\n"
            f"<script type=\"application/json\" id=\"fd-data\">{payload}</script>\n"
            f"<script>{bundle}</script>\n</body></html>\n")


def _check_out(out, inputs):
    """Refuses (ValueError) an out that is one of the inputs, exists and is not a regular file
    (featherdrive_common.check_outputs), or is not .html."""
    common.check_outputs([("--out", out)], inputs)
    if out.suffix.lower() not in (".html", ".htm"):
        raise ValueError(f"--out {out}: the page must be an .html file")


def _write_atomically(out, text, inputs):
    """Writes text to out through a temporary file beside it (_check_out first)."""
    _check_out(out, inputs)
    out.parent.mkdir(parents=True, exist_ok=True)
    common.write_atomically(out, lambda tmp: pathlib.Path(tmp).write_text(text, encoding="utf-8"))


def view(source, out=None, *, scene=None, robot=None, steps=None, packages=None, marker=None,
         title=None):
    """Writes the viewer page of a run and returns it (a ViewerPage; inline in Jupyter).

    source: a scene file (runs it), a trajectory CSV with scene= its scene (poses from its q
    columns), a Scene, or a Simulation (a copy stepped `steps` times, default 0: its state now;
    robot= its UrdfRobot or URDF file for the visuals, else shapes and inertia boxes). out: the
    .html (default out/<name>_view.html); steps: overrides the scene's; packages: {name: folder} for
    package:// meshes; marker: a link whose origin gets a magenta dot."""
    import featherdrive as fd
    # Every argument is checked before a file is read or a step run.
    if packages is not None and not isinstance(packages, dict):
        raise TypeError(f"packages must be a dict {{name: folder}}, not {type(packages).__name__}")
    packages = dict(packages or {})
    for name, folder in packages.items():
        if not isinstance(name, str) or not isinstance(folder, (str, os.PathLike)):
            raise TypeError(f"packages: {name!r}: {folder!r}: packages must map package names "
                            "(str) to folders")
    if steps is not None and (isinstance(steps, bool) or not isinstance(steps, int) or steps < 0):
        raise ValueError(f"steps = {steps!r} must be an integer >= 0")
    common.integer(steps, "steps", 0, MAX_STEPS, none=True)
    common.path(out, "out", none=True)
    common.optional_text(title, "title")
    common.optional_text(marker, "marker")
    if scene is not None and not isinstance(scene, (str, os.PathLike, fd.Scene)):
        raise TypeError(f"scene must be a scene path or a Scene, not {type(scene).__name__}")
    bundle = _read_bundle()
    notes = []
    inputs = [("the viewer's script", bundle_path())]
    csv_path = None
    if isinstance(source, fd.Simulation):
        stem = "simulation"
        if isinstance(robot, (str, os.PathLike)):
            inputs.append(("the URDF", pathlib.Path(robot)))
            robot = fd.load_urdf(robot)
        if robot is not None and not isinstance(robot, fd.UrdfRobot):
            raise TypeError(f"robot must be a UrdfRobot or a URDF path, not "
                            f"{type(robot).__name__}")
        if robot is not None and robot.model.link_names != source.model.link_names:
            raise ValueError(f"robot: the links of {robot.path} are not the simulation's")
    else:
        if isinstance(source, (str, os.PathLike)) and str(source).lower().endswith(".csv"):
            if scene is None:
                raise ValueError(f"{source}: a CSV needs the scene that ran it (scene=SCENE)")
            if steps is not None:
                raise ValueError(f"{source}: steps = {steps} is for a run of the scene; a CSV "
                                 "shows its own rows")
            csv_path = pathlib.Path(source)
            inputs.append(("the CSV", csv_path))
        else:
            scene = source
        if isinstance(scene, (str, os.PathLike)):
            scene = common.load_scene(scene)
        if not isinstance(scene, fd.Scene):
            raise TypeError(f"source must be a scene path, a CSV path, a Scene or a Simulation, "
                            f"not {type(scene).__name__}")
        robot = scene.robot
        inputs += common.scene_inputs(scene)
        stem = (csv_path or pathlib.Path(str(scene.path))).stem
    urdf_text, meshes = None, {}
    if robot is not None and str(robot.path):
        urdf_text, meshes, mesh_notes, mesh_files = _urdf_geometry(pathlib.Path(str(robot.path)),
                                                                   packages)
        inputs += [("a mesh", p) for p in mesh_files]
        notes += mesh_notes
    out = pathlib.Path(out if out is not None else pathlib.Path("out") / f"{stem}_view.html")
    _check_out(out, inputs)  # before the run
    if isinstance(source, fd.Simulation):
        run = _run_simulation(fd, source, steps or 0)
    elif csv_path is not None:
        run = _read_csv(fd, scene, csv_path)
    else:
        run = _run_scene(fd, scene, scene.steps if steps is None else steps, notes)
    data = _page_data(fd, run, robot, urdf_text, meshes, title or stem, marker)
    text = _html(data, bundle)
    _write_atomically(out, text, inputs)
    for note in notes:
        warnings.warn(note, stacklevel=2)
    return ViewerPage(out, text, len(data["times"]), notes)


# ---- the command ------------------------------------------------------------------------------

class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2
        sys.stderr.write(f"featherdrive view: {message} (see featherdrive view --help)\n")
        sys.exit(2)


def _package(text):
    name, sep, folder = text.partition("=")
    if not sep or not name or not folder:
        raise argparse.ArgumentTypeError(f"'{text}' is not NAME=DIR")
    if not os.path.isdir(folder):
        raise argparse.ArgumentTypeError(f"'{text}': {folder} is not a folder")
    return name, folder


def serve(page, port):
    """Serves the page's folder on 127.0.0.1 until Ctrl-C."""
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):  # no line per request
            pass
    handler = functools.partial(Quiet, directory=str(page.parent.resolve()))
    try:
        server = http.server.ThreadingHTTPServer(("127.0.0.1", port), handler)
    except OSError as exc:
        raise RuntimeError(f"--serve: cannot listen on 127.0.0.1:{port}: {exc.strerror}") from None
    url = f"http://127.0.0.1:{server.server_address[1]}/{page.name}"
    print(f"  serving {url} (Ctrl-C stops)", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()


def main(argv=None):
    parser = _Parser(
        prog="featherdrive view",
        description="Writes one self-contained HTML page that plays a run on the robot in 3D, "
                    "with a timeline and per-joint curves of q, target and drive force "
                    "(docs/viewer.md).")
    parser.add_argument("scene", help="scene file (YAML or JSON); it runs unless --csv is given")
    parser.add_argument("--csv", metavar="RUN.csv",
                        help="a trajectory of the scene (featherdrive simulate --out): the page "
                             "shows it instead of running the scene")
    parser.add_argument("--out", metavar="PAGE.html",
                        help="the page (default out/<scene or CSV name>_view.html)")
    parser.add_argument("--package", metavar="NAME=DIR", type=_package, action="append",
                        default=[], help="where package://NAME/ meshes are (repeatable)")
    parser.add_argument("--steps", type=int, help="steps to run (default: the scene's)")
    parser.add_argument("--marker", metavar="LINK",
                        help="a magenta dot at LINK's origin, drawn over everything")
    parser.add_argument("--serve", action="store_true",
                        help="then serve the page on 127.0.0.1 until Ctrl-C")
    parser.add_argument("--port", type=int,
                        help="the port of --serve (default 8000; 0: any free port)")
    args = parser.parse_args(argv)
    if args.steps is not None and args.steps < 0:
        parser.error(f"--steps {args.steps}: must be >= 0")
    if args.port is not None and not args.serve:
        parser.error(f"--port {args.port}: only with --serve")
    port = 8000 if args.port is None else args.port
    if not 0 <= port <= 65535:
        parser.error(f"--port {port}: must be in 0..65535")
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            source = args.csv if args.csv else args.scene
            page = view(source, args.out, scene=args.scene if args.csv else None,
                        steps=args.steps, packages=dict(args.package), marker=args.marker)
        for w in caught:
            sys.stderr.write(f"featherdrive view: warning: {_one_line(w.message)}\n")
    except (ValueError, ViewerUnavailable) as exc:
        sys.stderr.write(f"featherdrive view: {_one_line(exc)}\n")
        return 2
    except Exception as exc:  # noqa: BLE001 (a run failing: one line, exit 1)
        sys.stderr.write(f"featherdrive view: {_one_line(exc)}\n")
        return 1
    size = page.path.stat().st_size
    print(f"{args.csv or args.scene}: {page.frames} frames, {size / 1e6:.1f} MB")
    print(f"  page: {page.path}")
    if args.serve:
        try:
            serve(page.path, port)
        except RuntimeError as exc:
            sys.stderr.write(f"featherdrive view: {_one_line(exc)}\n")
            return 1
    return 0


def _one_line(exc):
    return " ".join(str(exc).split("\n"))


if __name__ == "__main__":
    sys.exit(main())
