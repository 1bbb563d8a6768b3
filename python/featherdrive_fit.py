"""Identify drive and joint parameters from a logged trajectory (docs/fitting.md).

    fit(scene, data, client=None, threads=None, out=None) -> FitResult
    python -m featherdrive_fit SCENE --data LOG.csv [--out DIR] [--scheduler ADDRESS]

The scene's ``fit:`` section names the unknowns and their bounds; the log's targets are replayed
in a Batch with candidate parameters and SciPy's ``least_squares`` matches the simulated q to the
logged q. Every simulation of a residual or a Jacobian is one Batch (one environment per
parameter set and segment), shipped as scene text + parameters, so it runs the same in-process or
on Dask workers.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import pathlib
import sys
import tempfile
import time

import numpy as np

import featherdrive as fd
import featherdrive_common as common
import featherdrive_distributed

# Forward differences: the step relative to a parameter's scale (its starting value, or its
# bounds' width when that is 0). The simulation is deterministic, so the error is truncation.
_FD_STEP = 1e-6
# The log's time steps must equal the scene's dt within this (relative), unless resampled.
_DT_TOLERANCE = 1e-6
# The most steps of a log on the scene's grid (resample: linear makes them from the time span):
# checked before the grid is made.
MAX_LOG_STEPS = 1_000_000
# An unknown starting at 0 has no magnitude of its own: it is scaled by its bounds' range, which
# is bounded so that the steps of the fit (fractions of it) stay steps.
MAX_ZERO_START_RANGE = 1e6
# With threads=None a batch of fewer environments than this runs on 1 thread: a small batch's
# step is shorter than the threads' meeting at every step (the arm example, 7 environments:
# 3.7 s on 1 thread, 9.4 s on 2 cores).
SMALL_BATCH = 64
# A fit running longer than this (s) prints a line per evaluation with verbose.
PROGRESS_AFTER = 2.0
# The most batches one evaluation is cut into (fit's chunks=).
MAX_CHUNKS = 4096
# The search's tolerances (xtol, ftol, gtol) and its evaluation limit per delay.
TOLERANCE = 1e-12
MAX_NFEV = 100
# The delay search (docs/fitting.md, "The delay"): every delay first runs a short search that
# stops once a step lowers the cost by less than SHORT_FTOL of it (or after SHORT_NFEV
# evaluations); a delay whose short-search cost is within REFINE_FACTOR of the lowest is then
# refined to TOLERANCE from where it stopped. A delay left out would need refining to lower its
# cost by more than REFINE_FACTOR to win; it lowered every delay's by at most 0.1 % (the tests'
# logs, the worked example's, logs with noise 1e-3 to 3e-2 rad), and a short search stopped by a
# shrunken trust region could stop further off: 2 leaves room for that.
SHORT_FTOL = 1e-3
SHORT_NFEV = 30
REFINE_FACTOR = 2.0

_DRIVE = ("stiffness", "damping", "max_force")
_FRICTION = {"friction.static": 0, "friction.dynamic": 1, "friction.viscous": 2}


@dataclasses.dataclass
class Log:
    """A log on the scene's time grid: row k is t0 + k dt. targets[k] drives step k -> k + 1."""
    t: np.ndarray               # (T,)
    q: np.ndarray               # (T, nv), dof order
    qd: np.ndarray | None       # (T, nv) or None when the log has no qd columns
    target_position: np.ndarray  # (T, nv), 0 on dofs without a drive
    target_velocity: np.ndarray  # (T, nv)


@dataclasses.dataclass
class Estimate:
    """One fitted unknown: a quantity on one joint (or link), or shared by several."""
    quantity: str
    names: list[str]
    value: float
    initial: float
    lower: float
    upper: float
    ci95: float  # half-width of the 95 % interval; nan where the Jacobian does not determine it


@dataclasses.dataclass
class FitResult:
    estimates: list[Estimate]
    delay: int | None            # the fitted delay (steps), None when it is not fitted
    # Per delay tried, ½ |r|² where its search ended: refined_delays' after the full search, the
    # others' after the short one (docs/fitting.md, "The delay").
    cost_by_delay: dict[int, float]
    refined_delays: list[int]    # the delays searched to the full tolerances
    rms_by_joint: dict[str, float]  # RMS q residual per joint at the optimum, rad or m
    rms: float
    nfev: int                    # parameter sets simulated
    converged: bool              # least_squares met a tolerance (not its evaluation limit)
    q_fitted: np.ndarray         # (T, nv) simulated q at the optimum, segments joined; nan
    #                              before the replay's start row (the largest delay)
    log: Log
    scene_file: str | None = None
    plot_file: str | None = None

    def value(self, quantity: str, name: str) -> float:
        """The fitted value of quantity on a joint (or link)."""
        for e in self.estimates:
            if e.quantity == quantity and name in e.names:
                return e.value
        raise ValueError(f"fit: {quantity} of {name!r} was not fitted")

    def __repr__(self) -> str:
        values = ", ".join(f"{e.quantity}[{','.join(e.names)}]={e.value:.6g}"
                           for e in self.estimates)
        delay = "" if self.delay is None else f", delay={self.delay}"
        return (f"FitResult({values}{delay}, rms={self.rms:.3g}, nfev={self.nfev}, "
                f"converged={self.converged})")

    def table(self) -> str:
        lines = [f"{'quantity':22} {'joints':24} {'initial':>12} {'fitted':>12} {'± 95 %':>10}"]
        for e in self.estimates:
            names = ",".join(e.names) if len(e.names) <= 2 else f"{e.names[0]},... ({len(e.names)})"
            lines.append(f"{e.quantity:22} {names:24} {e.initial:12.6g} {e.value:12.6g} "
                         f"{e.ci95:10.3g}")
        if self.delay is not None:
            costs = lambda refined: ", ".join(
                f"{k}: {c:.3g}" for k, c in sorted(self.cost_by_delay.items())
                if (k in self.refined_delays) == refined)
            short = costs(False)
            lines.append(f"delay {self.delay} steps (cost by delay: {costs(True)}" +
                         (f"; after the short search: {short})" if short else ")"))
        if not self.converged:
            lines.append("NOT CONVERGED: least_squares stopped at its evaluation limit")
        lines.append("RMS q residual per joint: " +
                     ", ".join(f"{j} {v:.3g}" for j, v in self.rms_by_joint.items()))
        return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# The log


def _log_error(path, message):
    return ValueError(f"{path}: {message}")


def read_log(path, scene) -> Log:
    """Reads a featherdrive CSV (t, q:<joint>, optional qd:<joint>, target:<joint> for each
    driven joint, optional target_velocity:<joint>; other columns ignored) onto the scene's time
    grid (fit.data.resample). ValueError names the file, the column or row and the value."""
    path = os.fspath(path)
    model = scene.model
    if model.floating_base():
        raise _log_error(scene.path, "fit: robots with a fixed base are fitted (a floating "
                                     "root's pose is not a dof position)")
    rows = common.read_csv(path, "the log")
    if len(rows) < 3:
        raise _log_error(path, f"{max(len(rows) - 1, 0)} data rows: the log needs at least 2")
    header = rows[0]
    index = {}
    for i, name in enumerate(header):
        if name in index:
            raise _log_error(path, f"column {name!r} appears twice")
        index[name] = i
    time_name = "t" if "t" in index else "time" if "time" in index else None
    if time_name is None:
        raise _log_error(path, "missing column t (or time)")
    dofs = model.dof_names
    driven = [d.dof for d in scene.drives if str(d.drive.type) != "DriveType.none"]

    def column(name, required):
        if name not in index:
            if required:
                raise _log_error(path, f"missing column {name}")
            return None
        i = index[name]
        values = np.empty(len(rows) - 1)
        for r, row in enumerate(rows[1:], start=2):
            if len(row) != len(header):
                raise _log_error(path, f"row {r}: {len(row)} fields, the header has {len(header)}")
            values[r - 2] = common.decimal(row[i], f"{path}: row {r}: {name}")
        return values

    t = column(time_name, True)
    for r in range(1, len(t)):
        if not t[r] > t[r - 1]:
            raise _log_error(path, f"row {r + 2}: {time_name} = {t[r]!r} is not after the "
                                   f"previous row's {t[r - 1]!r} (time must increase)")
    q = np.stack([column(f"q:{n}", True) for n in dofs], axis=1)
    qd_cols = [column(f"qd:{n}", False) for n in dofs]
    have_qd = [c is not None for c in qd_cols]
    if any(have_qd) and not all(have_qd):
        raise _log_error(path, f"missing column qd:{dofs[have_qd.index(False)]} "
                               "(give qd for every joint or none)")
    qd = np.stack(qd_cols, axis=1) if all(have_qd) else None
    tp = np.zeros_like(q)
    tv = np.zeros_like(q)
    for d in driven:
        tp[:, d] = column(f"target:{dofs[d]}", True)
        v = column(f"target_velocity:{dofs[d]}", False)
        if v is not None:
            tv[:, d] = v

    dt = scene.options.dt
    if scene.fit.data.resample == "exact":
        if t.size - 1 > MAX_LOG_STEPS:
            raise _log_error(path, f"row {MAX_LOG_STEPS + 2}: the log has {t.size - 1} steps, "
                                   f"more than {MAX_LOG_STEPS}")
        steps = np.diff(t)
        bad = np.flatnonzero(np.abs(steps - dt) > _DT_TOLERANCE * dt)
        if bad.size:
            r = int(bad[0])
            raise _log_error(path, f"rows {r + 2}-{r + 3}: time step {steps[r]!r} s is not the "
                                   f"scene's dt {dt!r} s (set fit.data.resample: linear)")
        return Log(t, q, qd, tp, tv)
    # linear: q and qd interpolated at t0 + k dt; a target holds from its row until the next.
    spans = (t - t[0]) / dt * (1 + 1e-12)
    if spans[-1] > MAX_LOG_STEPS:
        r = int(np.argmax(spans > MAX_LOG_STEPS))
        raise _log_error(path, f"row {r + 2}: {time_name} = {t[r]!r} is {t[r] - t[0]:.6g} s after "
                               f"the first row: {spans[r]:.4g} steps of dt = {dt!r} s, more than "
                               f"{MAX_LOG_STEPS} (fit.data.resample: linear)")
    grid = t[0] + dt * np.arange(int(math.floor(spans[-1])) + 1)
    if grid.size < 2:
        raise _log_error(path, f"the log spans {t[-1] - t[0]!r} s, less than one dt = {dt!r} s")
    interp = lambda x: np.stack([np.interp(grid, t, x[:, j]) for j in range(x.shape[1])], 1)
    held = np.searchsorted(t, grid * (1 + 1e-12), side="right") - 1
    return Log(grid, interp(q), None if qd is None else interp(qd), tp[held], tv[held])


# ---------------------------------------------------------------------------------------------
# The unknowns


@dataclasses.dataclass
class _Unknown:
    quantity: str
    names: list[str]
    indices: list[int]
    initial: float
    lower: float
    upper: float
    scale: float


def _unknowns(spec, path):
    out = []
    for p in spec.parameters:
        if p.quantity == "delay":
            continue
        groups = [list(range(len(p.names)))] if p.shared else [[i] for i in range(len(p.names))]
        for g, members in enumerate(groups):
            initial = p.initial[g]
            scale = abs(initial) if initial != 0 else p.upper - p.lower
            if initial == 0 and scale > MAX_ZERO_START_RANGE:
                # least_squares starts strictly inside the bounds (1e-10 of the scale) and the
                # Jacobian steps 1e-6 of it: of [0, 1e308] that is 1e298 away from the start.
                raise ValueError(f"{path}: {p.key}: starts at 0 with bounds "
                                 f"[{p.lower:g}, {p.upper:g}]: "
                                 "an unknown starting at 0 is scaled by its bounds' range, which "
                                 f"must be at most {MAX_ZERO_START_RANGE:g}; give initial: (not "
                                 "0) or narrower bounds")
            out.append(_Unknown(p.quantity, [p.names[i] for i in members],
                                [p.indices[i] for i in members], initial, p.lower, p.upper,
                                scale))
    return out


def _delay_candidates(spec):
    """The delays to try and the dofs they act on; (None, []) without a delay to fit."""
    for p in spec.parameters:
        if p.quantity == "delay":
            return list(range(int(p.lower), int(p.upper) + 1)), list(p.indices)
    return None, []


# ---------------------------------------------------------------------------------------------
# One batch: P parameter sets x S segments, each an environment. Module-level and picklable so
# that Dask workers run it; its inputs are plain data (scene text, numbers, arrays).

_SCENES = {}


def _same_bytes(path, data):
    try:
        with open(path, "rb") as f:
            return f.read(len(data) + 1) == data
    except OSError:
        return False


def _scene_from_files(scene_text, scene_path, files):
    """The scene of scene_text (its model an absolute path) and files {absolute path: bytes}, the
    robot's files. Where the files are (this machine, or a worker that shares its folders) the
    robot is read in place, so that what the model reads besides them (an MJCF's <include>s and
    meshes) is found; elsewhere the files are written under a temporary folder that mirrors their
    absolute paths, so that relative references between them still hold."""
    key = (scene_text, scene_path, tuple(sorted(files.items())))
    if key not in _SCENES:
        if all(_same_bytes(p, data) for p, data in files.items()):
            scene = fd.parse_scene(scene_text, scene_path)
        else:
            # The scene holds the parsed robot: the files are not needed once it is read.
            with tempfile.TemporaryDirectory(prefix="featherdrive_fit_") as folder:
                mirror = lambda p: os.path.join(folder, os.path.relpath(p, os.sep))
                for p, data in files.items():
                    os.makedirs(os.path.dirname(mirror(p)), exist_ok=True)
                    with open(mirror(p), "wb") as f:
                        f.write(data)
                import yaml
                doc = yaml.safe_load(scene_text)
                doc["model"] = mirror(doc["model"])
                scene = fd.parse_scene(yaml.safe_dump(doc), mirror(scene_path))
        _SCENES.clear()
        _SCENES[key] = scene
    return _SCENES[key]


def simulate_batch(job):
    """job: dict(scene_text, scene_path, files, unknowns [(quantity, indices)], values (P, n),
    delays (nv,), starts (S,), length, q0 (S, nv), qd0 (S, nv), target_position (T, nv),
    target_velocity (T, nv), threads). Returns q (P, S, length, nv) and qd likewise."""
    scene = _scene_from_files(job["scene_text"], job["scene_path"], job["files"])
    values = np.asarray(job["values"], dtype=float)
    starts = np.asarray(job["starts"])
    P, S, L = values.shape[0], starts.size, job["length"]
    N = P * S
    batch = fd.Batch(fd.make_simulation(scene), N)
    threads = job["threads"]
    batch.set_num_threads(threads if threads is not None else 1 if N < SMALL_BATCH else 0)
    per_env = np.repeat(values, S, axis=0)  # env e = p S + s
    armature = friction = None
    rows = {}  # a row kind's field -> (N, nv)
    for u, (quantity, indices) in enumerate(job["unknowns"]):
        v = per_env[:, u]
        if quantity in _DRIVE or quantity == "friction_coefficient":
            for e in range(N):
                sim = batch.sim(e)
                for dof in indices:
                    if quantity == "friction_coefficient":
                        sim.set_friction_coefficient(dof, v[e])
                        continue
                    drive = sim.drive(dof)
                    setattr(drive, quantity, v[e])
                    if quantity == "max_force":
                        drive.max_impulse = math.inf
                    sim.set_drive(dof, drive)
        elif quantity == "armature":
            armature = np.array(batch.armature()) if armature is None else armature
            armature[:, indices] = v[:, None]
        elif quantity in _FRICTION:
            if friction is None:
                friction = [np.array(a) for a in batch.joint_friction()]
            friction[_FRICTION[quantity]][:, indices] = v[:, None]
        elif quantity == "mass_scale":
            for link in indices:
                batch.set_link_mass(link, v * scene.model.links[link].mass)
        elif "." in quantity and quantity not in _FRICTION:  # a row kind's field
            kind, field = quantity.split(".", 1)
            if quantity not in rows:
                rows[quantity] = np.array(batch.row_parameter(kind, field))
            rows[quantity][:, indices] = v[:, None]
    for quantity, values in rows.items():
        batch.set_row_parameter(*quantity.split(".", 1), values)
    if armature is not None:
        batch.set_armature(armature)
    if friction is not None:
        batch.set_joint_friction(*friction)
    # The log holds dof positions (a spherical axis's, not its quaternion): q from them.
    model = scene.model
    q0 = np.asarray(job["q0"])
    if model.nq != model.nv:
        q0 = np.array([fd.set_dof_positions(model, model.neutral_configuration(), None, row)
                       for row in q0])
    batch.set_q(np.tile(q0, (P, 1)))
    batch.set_qd(np.tile(job["qd0"], (P, 1)))
    tp, tv = job["target_position"], job["target_velocity"]
    delays = np.asarray(job["delays"])
    dofs = np.arange(tp.shape[1])[None, :]
    q = np.empty((N, L, tp.shape[1]))
    qd = np.empty_like(q)
    for k in range(L):
        # Per dof the target commanded `delay` steps earlier; before the log's first row, its
        # first (as the simulation's delay line does, eq. 9 of docs/math/explicit_actuators.md).
        rows = np.maximum(np.tile(starts + k, P)[:, None] - delays[None, :], 0)
        batch.set_drive_targets(tp[rows, dofs], tv[rows, dofs])
        batch.step()
        q[:, k] = batch.q if model.nq == model.nv else fd.dof_positions(model, batch.q)
        qd[:, k] = batch.qd
    shape = (P, S, L, tp.shape[1])
    return q.reshape(shape), qd.reshape(shape)




# ---------------------------------------------------------------------------------------------
# The fit


def _replay_start(scene, log, candidates):
    """The log row the replay starts at: the largest delay (the scene's or one tried), so that
    the targets in the pipe at its first step are logged ones, which a log cut from running
    motion does not hold before its first row. A log without qd starts at row 0, in the scene's
    initial state, the first row's targets taken as the earlier ones (docs/fitting.md)."""
    if log.qd is None:
        return 0
    start = max([0] + [d.delay for d in scene.drives] + list(candidates or []))
    if start > log.t.size - 2:
        raise ValueError(f"{scene.path}: the replay starts {start} rows into the log (the "
                         f"largest delay), and the log has {log.t.size} rows")
    return start


class _Problem:
    def __init__(self, scene, log, unknowns, client, threads, chunks, start=0):
        text = common.read_text(scene.path, "the scene")
        import yaml
        doc = yaml.safe_load(text)
        scene_path = os.path.abspath(os.fspath(scene.path))
        model_path = os.path.abspath(os.fspath(scene.model_path))
        doc["model"] = model_path
        # The robot's files, shipped to workers that may not have them (_scene_from_files).
        files = {p: common.read_bytes(p, "the scene's model")
                 for what, p in common.scene_inputs(scene) if what != "the scene"}
        files = {os.path.abspath(p): data for p, data in files.items()}
        # The drives' delays are applied to the logged targets (simulate_batch), so that a
        # segment starts with the targets the robot had in the pipe: none in the simulation.
        for entry in [doc.get("drive_defaults")] + list((doc.get("drives") or {}).values()):
            if isinstance(entry, dict) and "delay" in entry:
                entry["delay"] = 0
        self.scene_delays = np.zeros(scene.model.nv, dtype=int)
        for d in scene.drives:
            self.scene_delays[d.dof] = d.delay
        self.base = dict(scene_text=yaml.safe_dump(doc), scene_path=scene_path, files=files,
                         unknowns=[(u.quantity, u.indices) for u in unknowns],
                         target_position=log.target_position,
                         target_velocity=log.target_velocity, threads=threads)
        self.unknowns = unknowns
        self.scale = np.array([u.scale for u in unknowns])
        self.client, self.chunks = client, chunks
        self.log = log
        T = log.t.size
        L = scene.fit.data.segment_steps or (T - 1 - start)
        if scene.fit.data.segment_steps and log.qd is None:
            raise ValueError(f"{scene.path}: fit.data.segment_steps = {L}: segments start from "
                             "the logged qd, and the log has no qd columns")
        L = min(L, T - 1 - start)
        # Whole segments from row `start`; a tail shorter than L is left out.
        self.starts = np.arange(start, T - L, L)
        self.length = L
        qd0 = log.qd[self.starts] if log.qd is not None else np.tile(scene.qd0, (1, 1))
        self.base.update(starts=self.starts, length=L, q0=log.q[self.starts], qd0=qd0)
        rows = self.starts[:, None] + 1 + np.arange(L)[None, :]
        self.q_ref = log.q[rows]  # (S, L, nv)
        self.qd_ref = None if log.qd is None else log.qd[rows]
        self.qd_weight = scene.fit.data.qd_weight if log.qd is not None else 0.0
        self.delays = self.scene_delays.copy()
        self.nfev = 0
        self.evaluations = 0
        self.verbose = False
        self.started = time.monotonic()

    def run(self, values):
        """q, qd (P, S, L, nv) for parameter rows `values` (physical units)."""
        values = np.atleast_2d(values)
        parts = np.array_split(np.arange(values.shape[0]), min(self.chunks, values.shape[0]))
        jobs = [dict(self.base, values=values[p], delays=self.delays) for p in parts]
        results = featherdrive_distributed.map_ordered(simulate_batch, jobs, client=self.client)
        self.nfev += values.shape[0]
        self.evaluations += 1
        if self.verbose and time.monotonic() - self.started > PROGRESS_AFTER:
            print(f"fit: evaluation {self.evaluations}, {self.nfev} parameter sets simulated, "
                  f"{time.monotonic() - self.started:.1f} s", file=sys.stderr, flush=True)
        return (np.concatenate([r[0] for r in results]), np.concatenate([r[1] for r in results]))

    def residuals(self, q, qd):
        r = (q - self.q_ref).reshape(q.shape[0], -1)
        if self.qd_weight:
            r = np.concatenate([r, self.qd_weight * (qd - self.qd_ref).reshape(q.shape[0], -1)], 1)
        return r

    # least_squares works in x = value / scale.
    def fun(self, x):
        return self.residuals(*self.run(x * self.scale))[0]

    def jac(self, x):
        # One batch: the point and each forward (backward at an upper bound) step.
        n = x.size
        h = np.full(n, _FD_STEP)
        upper = np.array([u.upper for u in self.unknowns]) / self.scale
        h[x + h > upper] *= -1
        rows = np.vstack([x, x + np.diag(h)])
        r = self.residuals(*self.run(rows * self.scale))
        return ((r[1:] - r[0]) / h[:, None]).T


def _confidence(J, r, m, n):
    """95 % half-widths from cov = s^2 (J^T J)^-1, s^2 = |r|^2 / (m - n) (docs/fitting.md)."""
    from scipy import stats
    if m <= n:
        return np.full(n, np.nan)
    s2 = float(r @ r) / (m - n)
    JtJ = J.T @ J
    try:
        cov = s2 * np.linalg.inv(JtJ)
    except np.linalg.LinAlgError:
        return np.full(n, np.nan)
    var = np.diag(cov)
    return np.where(var >= 0, stats.t.ppf(0.975, m - n) * np.sqrt(np.abs(var)), np.nan)


def _delay_search(problem, candidates, delayed, x0, lower, upper, verbose):
    """The delay and the unknowns (x) of the lowest cost: (K, x, converged, cost by delay,
    refined delays). Without a delay to fit (candidates None) one full search at the scene's
    delays; with one candidate or no unknowns, a full search (or the cost) per delay; otherwise
    a short search per delay and the close ones refined (docs/fitting.md, "The delay")."""
    from scipy.optimize import least_squares

    def search(K, x, ftol, max_nfev):
        problem.delays = problem.scene_delays.copy()
        problem.delays[delayed] = K
        if x.size == 0:  # nothing to fit: the cost at the scene's values
            r = problem.fun(x)
            return x, 0.5 * float(r @ r), True, 1
        sol = least_squares(problem.fun, x, jac=problem.jac, bounds=(lower, upper),
                            method="trf", x_scale=1.0, xtol=TOLERANCE, ftol=ftol,
                            gtol=TOLERANCE, max_nfev=max_nfev)
        return sol.x, float(sol.cost), sol.status > 0, sol.nfev

    def say(K, cost, what):
        if verbose:
            print(f"delay {K}: cost {cost:.6g} ({what})", file=sys.stderr, flush=True)

    if candidates is None or len(candidates) == 1 or x0.size == 0:
        best = None
        costs = {}
        for K in candidates if candidates is not None else [0]:
            x, cost, converged, _ = search(K, x0, TOLERANCE, MAX_NFEV)
            costs[K] = cost
            if candidates is not None:
                say(K, cost, "full search")
            if best is None or cost < best[1]:
                best = (K, cost, x, converged)
        return best[0], best[2], best[3], costs, sorted(costs) if candidates else []
    short = {}
    for K in candidates:
        x, cost, _, nfev = search(K, x0, SHORT_FTOL, SHORT_NFEV)
        short[K] = (x, cost, nfev)
        say(K, cost, f"short search, {nfev} evaluations")
    lowest = min(c for _, c, _ in short.values())
    costs = {K: c for K, (_, c, _) in short.items()}
    if verbose:
        print(f"refining the delays whose cost is within {REFINE_FACTOR:g} x the lowest, "
              f"{lowest:.6g}", file=sys.stderr, flush=True)
    best = None
    refined = []
    for K in candidates:  # in order: of equal costs the smaller delay wins
        x, cost, nfev = short[K]
        if not cost <= REFINE_FACTOR * lowest:
            continue
        x, cost, converged, _ = search(K, x, TOLERANCE, MAX_NFEV - nfev)
        costs[K] = cost
        refined.append(K)
        say(K, cost, "refined")
        if best is None or cost < best[1]:
            best = (K, cost, x, converged)
    return best[0], best[2], best[3], costs, refined


def fit(scene, data, client=None, threads=None, out=None, chunks=None, verbose=False):
    """Fits the scene's fit: unknowns to the log `data` (a CSV path).

    scene: a scene file path or an fd.Scene with a fit: section. client: a dask.distributed
    Client (batches run on its workers, results gathered in order). threads: each batch's
    threads (None: 1 for batches under SMALL_BATCH environments, else all cores). out: a folder
    for <scene>_fitted.yaml, <scene>_fit.png and <scene>_fit.txt (the table), checked before
    the fit. verbose: the cost per delay, and a line per evaluation once the fit has run
    PROGRESS_AFTER seconds (the command sets it).
    chunks: batches per evaluation (default: the client's worker count, or 1).
    Returns a FitResult; bad input raises ValueError naming the file, key or column and value."""
    # Every argument is checked before a file is read.
    if not isinstance(scene, fd.Scene):
        common.path(scene, "scene")
    common.path(data, "data")
    common.client(client)
    common.integer(threads, "threads", 0, common.MAX_THREADS, none=True)
    common.path(out, "out", none=True)
    common.integer(chunks, "chunks", 1, MAX_CHUNKS, none=True)
    if not isinstance(verbose, bool):
        raise TypeError(f"verbose = {verbose!r}: must be a bool, not {type(verbose).__name__}")
    if not isinstance(scene, fd.Scene):
        scene = common.load_scene(scene)
    if scene.fit is None:
        raise ValueError(f"{scene.path}: no fit: section (the parameters to identify)")
    outputs = _check_outputs(scene, data, out)  # before the fit: a refused output costs nothing
    log = read_log(data, scene)
    unknowns = _unknowns(scene.fit, scene.path)
    if chunks is None:
        chunks = len(client.scheduler_info()["workers"]) if client is not None else 1
    candidates, delayed = _delay_candidates(scene.fit)
    start = _replay_start(scene, log, candidates)
    problem = _Problem(scene, log, unknowns, client, threads, max(chunks, 1), start)
    problem.verbose = verbose
    lower = np.array([u.lower for u in unknowns]) / problem.scale
    upper = np.array([u.upper for u in unknowns]) / problem.scale
    x0 = np.array([u.initial for u in unknowns]) / problem.scale
    K, x, converged, costs, refined = _delay_search(problem, candidates, delayed, x0, lower,
                                                    upper, verbose)
    problem.delays = problem.scene_delays.copy()
    problem.delays[delayed] = K
    q, qd = problem.run(x * problem.scale)
    r = problem.residuals(q, qd)[0]
    ci = np.zeros(0)
    if unknowns:
        J = problem.jac(x) / problem.scale[None, :]
        ci = _confidence(J, r, r.size, x.size)
    values = x * problem.scale
    estimates = [Estimate(u.quantity, u.names, float(v), u.initial, u.lower, u.upper, float(c))
                 for u, v, c in zip(unknowns, values, ci)]
    q_fit = np.vstack([log.q[problem.starts[:1]], q[0].reshape(-1, q.shape[-1])])
    err = q_fit - log.q[start:start + q_fit.shape[0]]
    q_fit = np.vstack([np.full((start, q_fit.shape[1]), np.nan), q_fit])  # row k is log row k
    rms_by_joint = {n: float(np.sqrt(np.mean(err[:, d] ** 2)))
                    for d, n in enumerate(scene.model.dof_names)}
    result = FitResult(estimates, K if candidates is not None else None, costs, refined,
                       rms_by_joint, float(np.sqrt(np.mean(err ** 2))), problem.nfev, converged,
                       q_fit, log)
    if out is not None:
        _write_outputs(result, scene, outputs)
    return result


# ---------------------------------------------------------------------------------------------
# Outputs


def _check_outputs(scene, data, out):
    """The output files (scene, plot, report) in the folder out, checked as the commands check
    them (featherdrive_common.check_outputs); None without out."""
    if out is None:
        return None
    out = os.fspath(out)
    if os.path.exists(out) and not os.path.isdir(out):
        raise ValueError(f"out {out}: exists and is not a folder")
    stem = os.path.splitext(os.path.basename(os.fspath(scene.path)))[0]
    paths = [os.path.join(out, f"{stem}{suffix}")
             for suffix in ("_fitted.yaml", "_fit.png", "_fit.txt")]
    common.check_outputs([("out", p) for p in paths],
                         common.scene_inputs(scene) + [("the log", os.fspath(data))])
    return paths


def fitted_scene_text(result, scene):
    """The scene file with the fitted values written in (model path made absolute)."""
    import yaml
    doc = yaml.safe_load(common.read_text(scene.path, "the scene"))
    doc["model"] = os.path.abspath(os.fspath(scene.model_path))
    for e in result.estimates:
        for name in e.names:
            if e.quantity in _DRIVE:
                drive = doc.setdefault("drives", {}).setdefault(name, {})
                if "type" not in drive and "drive_defaults" not in doc:
                    drive["type"] = "force"
                drive[e.quantity] = e.value
                if e.quantity == "max_force":
                    drive.pop("max_impulse", None)
            elif e.quantity in ("armature", "friction_coefficient"):
                doc.setdefault("joints", {}).setdefault(name, {})[e.quantity] = e.value
            elif e.quantity in _FRICTION:
                joint = doc.setdefault("joints", {}).setdefault(name, {})
                joint.setdefault("friction", {})[e.quantity.split(".")[1]] = e.value
            elif "." in e.quantity:  # a row kind's field: joints.J.<kind>.<field>
                kind, field = e.quantity.split(".", 1)
                joint = doc.setdefault("joints", {}).setdefault(name, {})
                joint.setdefault(kind, {})[field] = e.value
    if result.delay is not None:
        for p in scene.fit.parameters:
            if p.quantity == "delay":
                for name in p.names:
                    doc.setdefault("drives", {}).setdefault(name, {})["delay"] = result.delay
    for p in doc.get("fit", {}).get("parameters", []):
        p.pop("initial", None)  # the scene's values are now the fitted ones
    return yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=100)


def _write_text(path, text):
    with open(path, "w") as f:
        f.write(text)


def _write_outputs(result, scene, outputs):
    scene_path, plot_path, report_path = outputs
    os.makedirs(os.path.dirname(scene_path) or ".", exist_ok=True)
    text = fitted_scene_text(result, scene)
    common.write_atomically(scene_path, lambda p: _write_text(p, text))
    notes = [f"mass_scale of {', '.join(e.names)} = {e.value:.6g}: not a scene key; scale the "
             "URDF's <inertial>" for e in result.estimates if e.quantity == "mass_scale"]
    common.write_atomically(report_path, lambda p: _write_text(
        p, result.table() + "\n" + "".join(n + "\n" for n in notes)))
    common.write_atomically(plot_path, lambda p: plot(result, scene, p))
    result.scene_file, result.plot_file = scene_path, plot_path


def plot(result, scene, path):
    """Per joint: logged and fitted q, and below it the residual (fitted - logged), as a PNG."""
    from matplotlib.figure import Figure  # not pyplot: no backend chosen, no global state
    names = scene.model.dof_names
    n = len(names)
    cols = min(n, 4)
    rows = (n + cols - 1) // cols
    width, height = 3.0 * cols, 2.6 * rows
    fig = Figure(figsize=(width, height))
    # A fixed layout in inches, sized for its fonts (6 pt ticks, 8 pt titles): cheaper than
    # constrained layout, which draws the figure twice to measure it.
    left, right, top, bottom = 0.6, 0.1, 0.35, 0.45  # 0.45: x tick labels and "t [s]"
    wgap, pair_gap, row_gap = 0.55, 0.15, 0.5  # pair_gap: the residual's "1e-5" offset
    cell_w = (width - left - right - (cols - 1) * wgap) / cols
    cell_h = (height - top - bottom - (rows - 1) * row_gap) / rows - pair_gap
    t = result.log.t[:result.q_fitted.shape[0]]
    for d, name in enumerate(names):
        x = left + (d % cols) * (cell_w + wgap)
        y_low = height - top - (d // cols + 1) * (cell_h + pair_gap) - (d // cols) * row_gap
        y_top = y_low + cell_h / 4 + pair_gap  # heights 3 : 1
        top_ax = fig.add_axes([x / width, y_top / height, cell_w / width,
                               cell_h * 3 / 4 / height])
        low = fig.add_axes([x / width, y_low / height, cell_w / width, cell_h / 4 / height],
                           sharex=top_ax)
        top_ax.plot(t, result.log.q[:t.size, d], "k-", lw=1.5, label="logged")
        top_ax.plot(t, result.q_fitted[:, d], "r--", lw=1, label="fitted")
        low.plot(t, result.q_fitted[:, d] - result.log.q[:t.size, d], "r-", lw=0.5)
        # y and pad fixed (above a "1e-5" offset) spare matplotlib measuring the axes to place it
        top_ax.set_title(f"{name} (rms {result.rms_by_joint[name]:.2g})", fontsize=8, y=1,
                         pad=12)
        top_ax.tick_params(labelsize=6, labelbottom=False)
        low.tick_params(labelsize=6)
        low.yaxis.get_offset_text().set_fontsize(6)
        for ax in (top_ax, low):  # placed labels: no second tick pass per axis to place them
            ax.xaxis.set_label_coords(0.5, -0.3)
            ax.yaxis.set_label_coords(-0.5 / cell_w, 0.5)
        if d == 0:
            top_ax.legend(fontsize=6)
            low.set_ylabel("residual", fontsize=6)
    fig.supxlabel("t [s]", fontsize=8, y=0.08 / height, va="bottom")
    fig.savefig(path, format="png", dpi=70)


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2
        sys.stderr.write(f"featherdrive fit: {message} (see featherdrive fit --help)\n")
        sys.exit(2)


def main(argv=None):
    parser = _Parser(prog="featherdrive fit",
                                     description="Fit a scene's fit: parameters to a log.")
    parser.add_argument("scene")
    parser.add_argument("--data", required=True, help="the log, a CSV")
    parser.add_argument("--out", help="folder for the outputs (default: out/<scene name>_fit, the "
                        "commands' one convention)")
    parser.add_argument("--scheduler", help="a Dask scheduler's address")
    parser.add_argument("--threads", type=int,
                        help="threads per batch (default: 1 for small batches, else all cores)")
    args = parser.parse_args(argv)
    client = None
    try:
        if args.scheduler:
            client = featherdrive_distributed.connect(args.scheduler)
        out = args.out or os.path.join("out", f"{pathlib.Path(args.scene).stem}_fit")
        result = fit(args.scene, args.data, client=client, threads=args.threads, out=out,
                     verbose=True)
    except ValueError as e:
        print(f"featherdrive fit: {' '.join(str(e).splitlines())}", file=sys.stderr)
        return 2
    except Exception as e:  # one line, as the CLI's other commands
        print(f"featherdrive fit: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    finally:
        if client is not None:
            client.close()
    print(result.table())
    print(f"wrote {result.scene_file}, {result.plot_file}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
