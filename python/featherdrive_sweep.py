"""Tracking error over a grid of drive gains: ``featherdrive sweep`` and ``fd.sweep``.

Every grid point is one environment of a Batch that runs the scene with those gains. Per drive,
from the error e = target - q at the end of each step (t = dt .. T) and the initial error e0:
rms, the RMS of e over the run (``featherdrive simulate``'s rms error); overshoot, for a step
(a target constant over the run and more than STEP_MIN from q(0)) the largest excursion past the
target, max(0, max -sign(e0) e) / |e0| (a fraction of the step), and for any other target the
largest |e| [rad or m]; settling_time [s], the first sample time from which |e| stays within the
band (SETTLING_BAND of |e0| for a step, of the target's range over the run otherwise,
SETTLING_BAND_ABSOLUTE where both are 0), 0 if e0 is inside, inf if the last step is outside;
max_force, the largest |drive force| over the steps [N or Nm]. One of them (rms by default) is
the objective that best() and the plot use.
Locally the whole grid is one Batch on all cores; with a Dask client the grid is cut into chunks
of rows, each shipped to a worker as (scene path, scene text, rows) and run there as a Batch, and
the results are gathered in grid order (featherdrive_distributed.map_ordered). Each environment
gives the same bits whatever the threads and the batch size (docs/conventions.md, "Batch") and
the errors are reduced per point, so the numbers do not depend on threads, chunks or workers. docs/fitting.md, "Sweeps and Dask".

Grid syntax: ``NAME=SPEC[,NAME=SPEC...]`` with NAME ``stiffness`` or ``damping`` (the drives'), or a
row kind's field ``KIND.FIELD`` (``joint_spring.stiffness``, ``fd.row_kinds()``) set on the same
joints as the gains, and SPEC
``VALUE`` (one point), ``LO:HI:N`` (N points spaced linearly) or ``LO:HI:N:log`` (N points
spaced geometrically, LO > 0). The first name varies slowest. A grid has at most MAX_POINTS
points, refused before any is made.
"""

import argparse
import math
import os
import pathlib
import sys

import numpy as np

import featherdrive_common as common

__all__ = ["sweep", "parse_grid", "SweepResult", "main"]

PARAMETERS = ("stiffness", "damping")


def _row_fields():
    """The row kinds' fields as grid names, KIND.FIELD."""
    import featherdrive as fd
    return [f"{k['name']}.{f['name']}" for k in fd.row_kinds() for f in k["fields"]]


def _names():
    return ", ".join(list(PARAMETERS) + _row_fields())
# The most points of a grid (each is a simulation); the axes' product is checked before the grid
# is made. Run locally, the grid is run LOCAL_CHUNK environments at a time.
MAX_POINTS = 1_000_000
LOCAL_CHUNK = 4096
# What a sweep can minimise (module docstring); rms is the default.
OBJECTIVES = ("rms", "overshoot", "settling_time", "max_force")
# The settling band: this share of the step (or of the target's range over the run); a target
# that neither steps nor moves gets SETTLING_BAND_ABSOLUTE [rad or m]. A constant target counts
# as a step when it lies more than STEP_MIN [rad or m] from the initial position.
SETTLING_BAND = 0.02
SETTLING_BAND_ABSOLUTE = 1e-3
STEP_MIN = 1e-9


def _number(text, where, signed=False):
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{where} = {text!r}: must be a number") from None
    if not math.isfinite(value) or (value < 0.0 and not signed):
        raise ValueError(f"{where} = {text!r}: must be finite and >= 0")
    return value


def _axis(name, spec):
    """The values of one grid axis from LO:HI:N[:log|:lin] or VALUE."""
    where = f"--grid {name}={spec}"
    parts = spec.split(":")
    signed = name not in PARAMETERS  # a row kind's field: its own check (a reference may be < 0)
    if len(parts) == 1:
        return np.array([_number(parts[0], where, signed)]), False
    if len(parts) not in (3, 4):
        raise ValueError(f"{where}: expected VALUE, LO:HI:N or LO:HI:N:log")
    lo, hi = _number(parts[0], where + " LO", signed), _number(parts[1], where + " HI", signed)
    try:
        n = int(parts[2])
    except ValueError:
        raise ValueError(f"{where}: N = {parts[2]!r} must be a whole number of points") from None
    if n < 1 or n > 100_000:
        raise ValueError(f"{where}: N = {n} must be in [1, 100000]")
    if hi < lo:
        raise ValueError(f"{where}: HI = {parts[1]} is below LO = {parts[0]}")
    spacing = parts[3] if len(parts) == 4 else "lin"
    if spacing not in ("lin", "log"):
        raise ValueError(f"{where}: spacing {spacing!r} must be lin or log")
    if spacing == "log":
        if lo <= 0.0:
            raise ValueError(f"{where}: log spacing needs LO > 0, not {parts[0]}")
        return np.geomspace(lo, hi, n), True
    return np.linspace(lo, hi, n), False


def parse_grid(grid):
    """[(name, values, log)] from the grid text or a {name: values} mapping; ValueError naming
    the entry for bad syntax, an unknown or repeated name, or bad values."""
    if isinstance(grid, str):
        entries = []
        for item in grid.split(","):
            if "=" not in item:
                raise ValueError(f"--grid entry {item!r}: expected NAME=LO:HI:N[:log] "
                                 f"(NAME one of {_names()})")
            name, spec = (s.strip() for s in item.split("=", 1))
            entries.append((name, spec))
    elif isinstance(grid, dict):
        entries = list(grid.items())
        for name, _ in entries:
            if not isinstance(name, str):
                raise TypeError(f"grid: a name {name!r} must be a str, not {type(name).__name__}")
    else:
        raise TypeError(f"grid must be a str or a dict, not {type(grid).__name__}")
    if not entries:
        raise ValueError("the grid is empty")
    axes, seen = [], set()
    for name, spec in entries:
        if name not in PARAMETERS and name not in _row_fields():
            raise ValueError(f"--grid {name}: unknown parameter (expected one of "
                             f"{_names()})")
        if name in seen:
            raise ValueError(f"--grid {name}: given twice")
        seen.add(name)
        if isinstance(spec, str):
            values, log = _axis(name, spec)
        else:
            try:
                values = np.asarray(spec, dtype=float).ravel()
            except (TypeError, ValueError):
                raise ValueError(f"grid {name}: values must be numbers, not "
                                 f"{type(spec).__name__}") from None
            if values.size == 0 or not np.all(np.isfinite(values)) or (
                    name in PARAMETERS and np.any(values < 0)):
                raise ValueError(f"grid {name}: values must be finite, >= 0 and not empty")
            log = False
        axes.append((name, values, log))
    count = math.prod(len(a[1]) for a in axes)
    if count > MAX_POINTS:
        sizes = " x ".join(f"{a[0]} {len(a[1])}" for a in axes)
        raise ValueError(f"--grid: {sizes} = {count} points, more than {MAX_POINTS}: "
                         "sweep fewer points")
    return axes


class SweepResult:
    """A sweep's grid and objectives, rows in grid order (the first parameter slowest).

    names: the parameters; axes: their values; points (M, p): each point's values; joints: the
    drives' joints; units: each drive's position unit (rad or m); step: whether each drive's
    target is a step (module docstring). Per point and drive (M, len(joints)): rms (RMS of
    target - q), overshoot, settling_time [s], max_force [N or Nm]. total (M,): sqrt(mean over
    the drives of rms**2). objective_name: rms, overshoot, settling_time or max_force;
    objective (M,): that objective of the --joint, or over the drives (rms: total; the others:
    the largest). diverged (M,): points whose run diverged (nan). warning: None, or one line
    when the best point is on the grid's edge."""

    def __init__(self, axes, joints, joint, values, diverged, objective="rms", units=None,
                 step=None, gain_units=None):
        self.names = [a[0] for a in axes]
        self.axes = [a[1] for a in axes]
        self.log = [a[2] for a in axes]
        self.points = _points(axes)
        self.joints = list(joints)
        self.joint = joint
        self.rms = values["rms"]
        self.overshoot = values["overshoot"]
        self.settling_time = values["settling_time"]
        self.max_force = values["max_force"]
        self.diverged = diverged
        self.units = list(units) if units is not None else ["rad"] * len(self.joints)
        self.step = np.asarray(step if step is not None else [False] * len(self.joints))
        self.gain_units = gain_units or {}
        self.total = np.array([math.sqrt(math.fsum(r * r for r in row) / len(row))
                               for row in self.rms])
        self.objective_name = objective
        if joint:
            self.objective = values[objective][:, self.joints.index(joint)]
        elif objective == "rms":
            self.objective = self.total
        else:
            self.objective = np.max(values[objective], axis=1)  # nan stays nan
        self.warning = self._edge_warning()

    def best(self):
        """Index of the point with the least objective among those that did not diverge."""
        ok = np.flatnonzero(~self.diverged)
        if ok.size == 0:
            raise RuntimeError("every grid point diverged")
        return int(ok[np.argmin(self.objective[ok])])

    def _edge_warning(self):
        """One line when the best point is at an end of an axis of several values."""
        if self.diverged.all():
            return None
        best = self.points[self.best()]
        ends = [f"{n} = {v:.6g} is the {'least' if v == a[0] else 'largest'} value swept"
                for n, a, v in zip(self.names, self.axes, best)
                if len(a) > 1 and v in (a[0], a[-1])]
        if not ends:
            return None
        return (f"the least {self.label()} is on the grid's edge ({'; '.join(ends)}): the "
                "optimum may lie outside the grid; widen it there")

    def label(self):
        """The objective in words, with its scope."""
        words = {"rms": "rms error", "overshoot": "overshoot",
                 "settling_time": "settling time", "max_force": "max |drive force|"}
        what = words[self.objective_name]
        if self.joint:
            return f"{what} of {self.joint}"
        if self.objective_name == "rms":
            return "total rms error"
        return f"{what} (largest of the drives)"

    def unit(self):
        """The objective's unit: rad or m for errors, 1 (of the step) or rad/m for overshoot,
        s for settling time, N or Nm for forces; 'a or b' where the drives differ."""
        chosen = [self.joints.index(self.joint)] if self.joint else range(len(self.joints))
        if self.objective_name == "settling_time":
            return "s"
        units = []
        for d in chosen:
            u = self.units[d]
            if self.objective_name == "max_force":
                u = "N" if u == "m" else "Nm"
            elif self.objective_name == "overshoot" and self.step[d]:
                u = "fraction of the step"
            if u not in units:
                units.append(u)
        return " or ".join(units)

    def write_csv(self, path):
        header = (self.names + [f"rms:{j}" for j in self.joints] + ["rms_total", "diverged"]
                  + [f"{o}:{j}" for o in OBJECTIVES[1:] for j in self.joints])
        lines = [",".join(header)]
        for i in range(len(self.points)):
            values = list(self.points[i]) + list(self.rms[i]) + [self.total[i]]
            extra = [v for o in OBJECTIVES[1:] for v in getattr(self, o)[i]]
            lines.append(",".join(repr(float(v)) for v in values)
                         + f",{int(self.diverged[i])},"
                         + ",".join(repr(float(v)) for v in extra))
        text = "\n".join(lines) + "\n"
        common.write_atomically(path, lambda tmp: pathlib.Path(tmp).write_text(text))

    def plot(self, path, title):
        """Writes the PNG; returns the figure, whose labels can be read."""
        import matplotlib.colors
        from matplotlib.figure import Figure  # not pyplot: no backend chosen, no global state
        what = f"{self.label()} [{self.unit()}]"
        axis = [f"{n} [{self.gain_units[n]}]" if n in self.gain_units else n for n in self.names]
        best = self.best()
        varying = [i for i, a in enumerate(self.axes) if len(a) > 1]
        # A fixed layout in inches for 10 pt text (tight_layout measures every label first):
        # left, tick labels and the y label; bottom, the x ones; top, the title; right, the
        # colour bar (0.3 gap, 0.22 wide) and its tick labels and label.
        width, height = 7.0, 5.5
        left, bottom, top = 0.85, 0.6, 0.4
        right = 0.2 if len(varying) <= 1 else 0.3 + 0.22 + 1.05
        fig = Figure(figsize=(width, height))
        ax = fig.add_axes([left / width, bottom / height, 1 - (left + right) / width,
                           1 - (bottom + top) / height])
        if len(varying) <= 1:
            k = varying[0] if varying else 0
            ax.plot(self.points[:, k], self.objective, "o-")
            ax.plot(self.points[best, k], self.objective[best], "r*", markersize=14)
            ax.set_xlabel(axis[k])
            ax.set_ylabel(what)
            if self.log[k]:
                ax.set_xscale("log")
        elif len(varying) == 2:
            z = np.ma.masked_invalid(self.objective.reshape(len(self.axes[0]),
                                                            len(self.axes[1])))
            finite = self.objective[np.isfinite(self.objective)]
            mesh = ax.pcolormesh(_edges(self.axes[1], self.log[1]),
                                 _edges(self.axes[0], self.log[0]), z, shading="flat",
                                 norm=matplotlib.colors.LogNorm()
                                 if finite.size and finite.min() > 0 else None)
            bar = fig.add_axes([1 - (0.22 + 1.05) / width, bottom / height, 0.22 / width,
                                1 - (bottom + top) / height])
            fig.colorbar(mesh, cax=bar, label=what)
            ax.plot(self.points[best, 1], self.points[best, 0], "w*", markersize=14)
            ax.set_xlabel(axis[1])
            ax.set_ylabel(axis[0])
            if self.log[1]:
                ax.set_xscale("log")
            if self.log[0]:
                ax.set_yscale("log")
        else:
            raise ValueError(f"a plot shows one or two parameters, not {len(varying)}")
        ax.set_title(title)
        common.write_atomically(path, lambda tmp: fig.savefig(tmp, dpi=100, format="png"))
        return fig


def _edges(values, log):
    """Cell edges around grid values: midpoints, geometric ones on a log axis."""
    v = np.log(values) if log else np.asarray(values, dtype=float)
    mid = (v[1:] + v[:-1]) / 2
    edges = np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])
    return np.exp(edges) if log else edges


def _points(axes):
    mesh = np.meshgrid(*[a[1] for a in axes], indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=1)


def _drives(scene, joint):
    """The scene's implicit drives [(joint, dof)] and the dofs the grid changes."""
    import featherdrive as fd
    drives = [(d.joint, d.dof)
              for d in scene.drives if d.drive.type != fd.DriveType.none and d.actuator is None]
    if not drives:
        raise ValueError(f"{scene.path}: the scene has no implicit drive (type force or "
                         "acceleration) to sweep")
    names = [d[0] for d in drives]
    if joint is not None and joint not in names:
        raise ValueError(f"--joint {joint}: not an implicit drive of {scene.path} "
                         f"(its drives: {', '.join(names)})")
    changed = [d[1] for d in drives if joint is None or d[0] == joint]
    return drives, changed


def _steps_and_bands(specs, initial_error, steps, dt):
    """Per drive: whether its target is a step (constant over the run, away from the initial
    position) and the settling band [rad or m] (module docstring)."""
    step, band = [], []
    for spec, e0 in zip(specs, initial_error):
        path = np.array([spec.target_at(k * dt)[0] for k in range(steps + 1)])
        is_step = bool(np.all(path == path[0])) and abs(e0) > STEP_MIN
        span = abs(e0) if is_step else float(np.max(path) - np.min(path))
        step.append(is_step)
        band.append(SETTLING_BAND * span if span > 0 else SETTLING_BAND_ABSOLUTE)
    return np.array(step), np.array(band)


def _units(model, drives):
    """Each drive's position unit: m on a prismatic joint, rad otherwise."""
    import featherdrive as fd
    return ["m" if model.links[model.dof_link[dof]].joint_type == fd.JointType.prismatic
            else "rad" for _, dof in drives]


def _gain_units(scene, drives, changed):
    """The gains' units over the changed drives: N/m, Nm/rad (force drives) or 1/s², and Ns/m,
    Nms/rad or 1/s; 'a or b' where the drives differ."""
    import featherdrive as fd
    model = scene.model
    kinds = {"stiffness": [], "damping": []}
    for joint, dof in drives:
        if dof not in changed:
            continue
        spec = next(s for s in scene.drives if s.joint == joint)
        linear = model.links[model.dof_link[dof]].joint_type == fd.JointType.prismatic
        if spec.drive.type == fd.DriveType.acceleration:
            pair = ("1/s²", "1/s")
        else:
            pair = ("N/m", "Ns/m") if linear else ("Nm/rad", "Nms/rad")
        for name, unit in zip(kinds, pair):
            if unit not in kinds[name]:
                kinds[name].append(unit)
        # The joint spring's: a force law whatever the drive's type; its reference a position.
        spring = ("N/m", "Ns/m", "m") if linear else ("Nm/rad", "Nms/rad", "rad")
        for name, unit in zip(("joint_spring.stiffness", "joint_spring.damping",
                               "joint_spring.reference"), spring):
            kinds.setdefault(name, [])
            if unit not in kinds[name]:
                kinds[name].append(unit)
    return {name: " or ".join(u) for name, u in kinds.items()}


def evaluate(item):
    """The objectives of the rows of one chunk ({name: (k, drives)}, OBJECTIVES), diverged
    flags (k,) and which drives' targets are steps (drives,): item is (scene path, scene text,
    parameter names, rows (k, p), joint or None, threads). Module-level and of plain data, so
    that Dask ships it to workers."""
    import featherdrive as fd
    path, text, names, rows, joint, threads = item
    scene = fd.parse_scene(text, path)
    drives, changed = _drives(scene, joint)
    prototype = fd.make_simulation(scene)
    rows = np.atleast_2d(np.asarray(rows, dtype=float))
    batch = fd.Batch(prototype, len(rows))
    batch.num_threads = threads
    for i, row in enumerate(rows):
        env = batch.sim(i)
        for dof in changed:
            drive = env.drive(dof)
            for name, value in zip(names, row):
                if name in PARAMETERS:
                    setattr(drive, name, float(value))
                else:  # a row kind's field (the kind's own check refuses a bad value)
                    kind, field = name.split(".", 1)
                    env.set_row_parameters(kind, dof, **{field: float(value)})
            env.set_drive(dof, drive)
    # The scene's targets, the same for every environment: a reference simulation takes them
    # from fd.apply_targets (control steps and interpolation included) for set_drive_targets.
    reference = fd.make_simulation(scene)
    nv = scene.model.nv
    dt = scene.options.dt
    dofs = [d[1] for d in drives]
    specs = [next(s for s in scene.drives if s.joint == d[0]) for d in drives]
    squares = np.zeros((len(rows), len(drives)))
    alive = np.ones(len(rows), dtype=bool)
    position = np.zeros(nv)
    velocity = np.zeros(nv)
    # Overshoot, settling time and peak force (module docstring): the step heights, bands and
    # running extremes, from the same errors as the RMS.
    dofs = np.array([d[1] for d in drives])
    initial = np.array([s.target_at(0.0)[0] for s in specs]) - \
        fd.dof_positions(scene.model, batch.q, dofs)
    step, band = _steps_and_bands(specs, initial[0], scene.steps, dt)
    direction = np.where(step, -np.sign(initial[0]), 0.0)
    excursion = np.zeros((len(rows), len(drives)))
    settled_at = np.where(np.abs(initial) > band, dt, 0.0)
    peak_force = np.zeros((len(rows), len(drives)))
    for k in range(scene.steps):
        fd.apply_targets(scene, reference, k)
        for d in range(nv):
            target = reference.drive(d)
            position[d], velocity[d] = target.target_position, target.target_velocity
        batch.set_drive_targets(position, velocity)
        try:
            batch.step()
        except fd.DivergenceError:
            for i in np.flatnonzero(alive):
                if batch.sim(int(i)).step_count != k + 1:
                    alive[i] = False
        t = (k + 1) * dt
        target_q = np.array([s.target_at(t)[0] for s in specs])
        # Each drive's position as the CSV has it (a spherical axis: PhysX's, not a q entry).
        error = target_q - fd.dof_positions(scene.model, batch.q, dofs)
        squares += error * error
        excursion = np.maximum(excursion, np.where(step, direction * error, np.abs(error)))
        settled_at[np.abs(error) > band] = t + dt
        peak_force = np.maximum(peak_force, np.abs(batch.drive_force[:, dofs]))
    rms = np.sqrt(squares / max(scene.steps, 1))
    overshoot = np.where(step, excursion / np.where(step, np.abs(initial), 1.0), excursion)
    end = scene.steps * dt
    settling = np.where(settled_at > end + dt / 2, np.inf, settled_at)  # outside at the end
    values = {"rms": rms, "overshoot": overshoot, "settling_time": settling,
              "max_force": peak_force}
    for v in values.values():
        v[~alive] = np.nan
    return values, ~alive, step


def sweep(scene, grid, joint=None, client=None, num_threads=0, chunk_size=None,
          objective="rms"):
    """Runs the scene at every point of the grid; returns a SweepResult.

    scene: a scene file path; grid: the grid text (module docstring) or {name: values};
    joint: only this drive's gains change and its objective is the result's (default: every
    implicit drive's gains, the objective over the drives); objective: what best() and the plot
    minimise, one of OBJECTIVES (every one is computed); client: a distributed.Client (default: one
    Batch here); num_threads: the Batch's threads (0: all cores); chunk_size: grid points per
    task on the cluster (default: the grid shared evenly among the workers)."""
    import featherdrive as fd
    from featherdrive_distributed import map_ordered
    # Every argument is checked before the scene is read or a point made.
    path = os.fspath(common.path(scene, "scene"))
    common.optional_text(joint, "joint")
    common.client(client)
    common.integer(num_threads, "num_threads", 0, common.MAX_THREADS)
    common.integer(chunk_size, "chunk_size", 1, MAX_POINTS, none=True)
    _objective(objective, "objective")
    axes = parse_grid(grid)
    text = common.read_text(path, "the scene")
    parsed = fd.parse_scene(text, path)  # InputError (a ValueError) for a bad scene
    drives, changed = _drives(parsed, joint)
    # A row kind's field takes what its kind's check takes: each value tried once, before the run.
    probe = fd.make_simulation(parsed)
    for name, values, _ in axes:
        if name in PARAMETERS:
            continue
        kind, field = name.split(".", 1)
        for value in values:
            for dof in changed:
                probe.set_row_parameters(kind, dof, **{field: float(value)})
    points = _points(axes)
    names = [a[0] for a in axes]
    if client is None:
        chunk_size = LOCAL_CHUNK  # the environments of one Batch; the numbers do not depend on it
    elif chunk_size is None:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        chunk_size = -(-len(points) // workers)
    chunks = [points[i:i + chunk_size] for i in range(0, len(points), chunk_size)]
    items = [(path, text, names, rows, joint, num_threads) for rows in chunks]
    results = map_ordered(evaluate, items, client)
    values = {name: np.concatenate([r[0][name] for r in results]) for name in OBJECTIVES}
    diverged = np.concatenate([r[1] for r in results])
    return SweepResult(axes, [d[0] for d in drives], joint, values, diverged, objective,
                       _units(parsed.model, drives), results[0][2],
                       _gain_units(parsed, drives, changed))


def _objective(value, where):
    if not isinstance(value, str):
        raise TypeError(f"{where} = {value!r}: must be a str, not {type(value).__name__}")
    if value not in OBJECTIVES:
        raise ValueError(f"{where} = {value!r}: must be one of {', '.join(OBJECTIVES)}")


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2
        sys.stderr.write(f"featherdrive sweep: {message} (see featherdrive sweep --help)\n")
        sys.exit(2)


def main(argv=None):
    parser = _Parser(
        prog="featherdrive sweep",
        description="Tracking error (RMS of target - q over the run) of a scene's drives over a "
                    "grid of gains: a CSV of the grid and a plot (heat map for two parameters).",
        epilog="Grid: NAME=VALUE, NAME=LO:HI:N (linear) or NAME=LO:HI:N:log (geometric), "
               "comma-separated, NAME stiffness or damping; e.g. "
               "stiffness=10:1000:8:log,damping=1:100:8:log")
    parser.add_argument("scene", help="scene file (YAML or JSON)")
    parser.add_argument("--grid", required=True, help="the grid (see below)")
    parser.add_argument("--joint", help="change only this drive's gains; its objective is plotted")
    parser.add_argument("--objective", default="rms",
                        help="what the plot and the least point use: rms (the default), "
                             "overshoot, settling_time or max_force; the CSV has them all")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="run on the Dask cluster of this scheduler (tcp://host:8786)")
    parser.add_argument("--out", metavar="DIR",
                        help="folder for sweep.csv and sweep.png (default: out/<scene name>_sweep)")
    parser.add_argument("--threads", type=int, default=0,
                        help="threads of each Batch (0: all cores; the default)")
    args = parser.parse_args(argv)
    client = None
    try:
        out = pathlib.Path(args.out or pathlib.Path("out") / f"{pathlib.Path(args.scene).stem}_sweep")
        if out.exists() and not out.is_dir():
            raise ValueError(f"--out {out}: exists and is not a folder")
        axes = parse_grid(args.grid)
        if len(axes) > 2:
            raise ValueError(f"--grid: {len(axes)} parameters; a sweep plots one or two")
        common.integer(args.threads, "--threads", 0, common.MAX_THREADS)
        _objective(args.objective, "--objective")
        # The outputs are checked before the run: none may replace a file the run reads.
        scene = common.load_scene(args.scene)
        common.check_outputs([("--out", out / "sweep.csv"), ("--out", out / "sweep.png")],
                             common.scene_inputs(scene))
        if args.scheduler:
            from featherdrive_distributed import connect
            client = connect(args.scheduler)
        result = sweep(args.scene, args.grid, joint=args.joint, client=client,
                       num_threads=args.threads, objective=args.objective)
        out.mkdir(parents=True, exist_ok=True)
        result.write_csv(out / "sweep.csv")
        best = result.best()
        result.plot(out / "sweep.png", f"{pathlib.Path(args.scene).name}: "
                    + " x ".join(f"{n} ({len(a)})" for n, a in zip(result.names, result.axes)))
    except ValueError as exc:
        sys.stderr.write(f"featherdrive sweep: {_one_line(exc)}\n")
        return 2
    except Exception as exc:  # noqa: BLE001 (a run failing: one line, exit 1)
        sys.stderr.write(f"featherdrive sweep: {_one_line(exc)}\n")
        return 1
    finally:
        if client is not None:
            client.close()
    where = f" on {args.scheduler}" if args.scheduler else ""
    print(f"{args.scene}: {len(result.points)} grid points{where}, {len(result.joints)} drives")
    point = ", ".join(f"{n} {v:.6g}" for n, v in zip(result.names, result.points[best]))
    print(f"  least {result.label()}: {result.objective[best]:.4e} {result.unit()} at {point}")
    if result.warning:
        sys.stderr.write(f"featherdrive sweep: warning: {result.warning}\n")
    if result.diverged.any():
        print(f"  {int(result.diverged.sum())} grid points diverged (nan in the CSV, "
              "diverged = 1)")
    print(f"  grid: {out / 'sweep.csv'}")
    print(f"  plot: {out / 'sweep.png'}")
    return 0


def _one_line(exc):
    return " ".join(str(exc).split("\n"))


if __name__ == "__main__":
    sys.exit(main())
