#!/usr/bin/env node
'use strict';
// Self-check of the PhysX harness against closed-form results.
//
//   node selfcheck.js            (exit 0 when every check passes)
//
// Checks (float32 PhysX against double-precision closed forms):
//  1. slider, force drive, PGS 1/1 (and 4/2): implicit-Euler recurrence
//       m (v1 - v0) = dt (kp (xT - x0 - dt v1) + kd (vT - v1)),  x1 = x0 + dt v1
//     with a moving target; q, qd and the drive-force readback f, over 100 steps.
//  2. the same with armature, an acceleration drive, a saturated max force, and TGS
//     (n implicit sub-steps of dt/n towards the interpolated target).
//  3. a revolute joint about a skew axis with a full (non-diagonal) inertia tensor:
//     the same recurrence with the moment of inertia about the axis.
//  4. a pendulum under gravity: free swing (semi-implicit Euler recurrence, period,
//     energy) and a driven pendulum at rest (drive torque balances gravity).
//  5. drive-force readback on a 3-link revolute/prismatic/revolute chain against
//     inverse dynamics (PGS, TGS, armature), and on a floating base against the PD law.
//  6. a floating single body: its centre of mass moves in a straight line.

const { loadPhysX } = require('./physx_loader.js');
const H = require('./harness.js');

const DT = 1 / 60;
let failures = 0;

function link(name, parent, mass, com, inertia, joint) {
  return { name, parent, mass, com, inertia, joint: joint || null };
}
function baseScene(over) {
  return Object.assign({
    format: 'featherdrive-physx/2', dt: DT, steps: 100, gravity: [0, 0, -9.81],
    solver: { type: 'pgs', position_iterations: 1, velocity_iterations: 1 },
    drive_limits_are_forces: true, floating_base: false,
    root: { position: [0, 0, 0], quat: [1, 0, 0, 0] },
  }, over);
}
function run(P, doc) {
  const s = H.parseScene(JSON.parse(JSON.stringify(doc)));
  const r = H.simulate(P, s);
  if (r.asleep) throw new Error('articulation asleep');
  H.release(r.handle);
  const nj = r.handle.movableJoints.length;
  return r.rows.map((row) => ({
    q: row.slice(2, 2 + nj), qd: row.slice(2 + nj, 2 + 2 * nj), f: row.slice(2 + 2 * nj, 2 + 3 * nj),
    root: row.slice(2 + 3 * nj),
  }));
}
const f32 = Math.fround;
function maxAbs(a) { return a.reduce((m, x) => Math.max(m, Math.abs(x)), 0); }

function check(title, cond, detail) {
  console.log(`${cond ? 'PASS' : 'FAIL'} ${title}${detail ? '\n       ' + detail : ''}`);
  if (!cond) failures += 1;
}

// Target schedule used by the 1-dof checks: a moving sinusoid with its velocity.
function targetAt(k) {
  const t = k * DT;
  return [0.5 + 0.3 * Math.sin(3 * t), 0.9 * Math.cos(3 * t)];
}

// One closed-form PGS step on one dof: implicit PD law with effective mass meff (kp, kd
// in force units), optional clamp on the step's impulse. Returns {q, qd, f}.
function stepPGS(x, v, meff, kp, kd, xT, vT, maxImpulse = Infinity) {
  // fixed point: lambda = dt (kp (xT - x - dt v1) + kd (vT - v1)), v1 = v + lambda / meff
  let lambda = DT * (kp * (xT - x - DT * v) + kd * (vT - v)) / (1 + DT * (DT * kp + kd) / meff);
  lambda = Math.max(-maxImpulse, Math.min(maxImpulse, lambda));
  const v1 = v + lambda / meff;
  return { q: x + DT * v1, qd: v1, f: lambda / DT };
}
// One closed-form TGS step: n implicit sub-steps of h = dt/n towards the interpolated
// target xT - (dt - i h) vT; the step's force is the summed impulse / dt.
function stepTGS(n, x, v, meff, kp, kd, xT, vT) {
  const h = DT / n;
  let sum = 0;
  for (let i = 1; i <= n; ++i) {
    const xs = xT - (DT - i * h) * vT;
    const lambda = h * (kp * (xs - x - h * v) + kd * (vT - v)) / (1 + h * (h * kp + kd) / meff);
    v += lambda / meff;
    x += h * v;
    sum += lambda;
  }
  return { q: x, qd: v, f: sum / DT };
}

// Compares a 1-dof PhysX run with a closed-form step function two ways:
//  free run : the closed-form recurrence from the initial state over all steps;
//  per step : each PhysX step against the closed-form step taken from PhysX's own
//             previous state (isolates the per-step error, in particular of f, which
//             otherwise inherits kp times the trajectory's accumulated rounding).
function compareOneDof(title, got, stepFn, tol) {
  const free = [{ q: got[0].q[0], qd: got[0].qd[0], f: 0 }];
  const local = [free[0]];
  for (let k = 1; k < got.length; ++k) {
    const [xT, vT] = targetAt(k);
    const a = free[k - 1];
    free.push(stepFn(a.q, a.qd, xT, vT));
    local.push(stepFn(got[k - 1].q[0], got[k - 1].qd[0], xT, vT));
  }
  const ser = (want, keys) => Object.fromEntries(keys.map((key) => [key,
    [got.slice(1).map((r) => r[key][0]), want.slice(1).map((r) => r[key])]]));
  const r1 = compareSeries(ser(free, ['q', 'qd', 'f']), tol, 'free run');
  const r2 = compareSeries(ser(local, ['q', 'qd', 'f']), tol, 'per step');
  const ok = r1.ok && r2.ok;
  console.log(`${ok ? 'PASS' : 'FAIL'} ${title}\n       ${r1.text}\n       ${r2.text}`);
  if (!ok) failures += 1;
  return { free, local };
}
function compareSeries(series, tol, label) {
  // f is read back from velocity changes: its rounding is about m ulp(qd) / dt, which
  // relative to max |f| is a few 1e-6 when the drive is weak compared to the momentum.
  const tolOf = (name) => (name === 'f' ? 5 * tol : tol);
  const parts = [];
  let ok = true;
  for (const [name, [got, want]] of Object.entries(series)) {
    const scale = Math.max(maxAbs(want), 1e-30);
    let err = 0;
    for (let i = 0; i < want.length; ++i) err = Math.max(err, Math.abs(got[i] - want[i]));
    const rel = err / scale;
    if (!(rel <= tolOf(name))) ok = false;
    parts.push(`${name} ${rel.toExponential(1)}`);
  }
  return { ok, text: `${label}: max error / max |value|: ${parts.join(', ')}` };
}

function sliderDoc(opts = {}) {
  const m = opts.mass || 2.5;
  const drive = Object.assign({ type: 'force', stiffness: 400, damping: 20, max_force: 1e30,
    target_position: targetAt(0)[0], target_velocity: targetAt(0)[1] }, opts.drive || {});
  const targets = [];
  for (let k = 1; k <= 100; ++k) { const [p, v] = targetAt(k); targets.push({ j1: [p, v] }); }
  return baseScene({
    solver: opts.solver || { type: 'pgs', position_iterations: 1, velocity_iterations: 1 },
    links: [
      link('base', -1, 1, [0, 0, 0], [1, 1, 1, 0, 0, 0]),
      link('slider', 0, m, [0.1, -0.05, 0.2], [0.02, 0.03, 0.04, 0.001, 0, 0.002], {
        name: 'j1', type: 'prismatic', origin: { xyz: [0.3, 0, 0.1], quat: [1, 0, 0, 0] },
        axis: [1, 0, 0], armature: opts.armature || 0, drive,
      }),
    ],
    initial: { q: { j1: 0.1 }, qd: { j1: -0.2 } },
    targets,
  });
}
// Inverse dynamics (recursive Newton-Euler, double precision) of a fixed-base scene:
// joint forces tau = M(q) qdd + c(q, qd) - g(q) (+ armature qdd) for the movable joints.
function inverseDynamics(doc, qMap, qdMap, qddMap) {
  const links = doc.links;
  const n = links.length;
  const X = []; // per link: world rotation Q, origin p, w, dw, a (origin accel), s (axis world)
  const qr = H.qrot, qm = H.qmul;
  const cr = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const ad = (...vs) => vs.reduce((s, v) => [s[0] + v[0], s[1] + v[1], s[2] + v[2]]);
  const sc = (k, v) => [k * v[0], k * v[1], k * v[2]];
  const dt3 = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const g = doc.gravity;
  for (let i = 0; i < n; ++i) {
    const L = links[i];
    if (i === 0) {
      X.push({ Q: doc.root.quat, p: doc.root.position, w: [0, 0, 0], dw: [0, 0, 0], a: sc(-1, g) });
      continue;
    }
    const P0 = X[L.parent];
    const J = L.joint;
    const q = qMap[J.name] || 0, qd = qdMap[J.name] || 0, qdd = qddMap[J.name] || 0;
    const Qo = qm(P0.Q, J.origin.quat);
    const s = J.type === 'fixed' ? [0, 0, 0] : qr(Qo, J.axis);
    let Q = Qo, r = qr(P0.Q, J.origin.xyz);
    let w = P0.w, dw = P0.dw;
    let a = ad(P0.a, cr(P0.dw, r), cr(P0.w, cr(P0.w, r)));
    if (J.type === 'revolute') {
      const h = q / 2;
      Q = qm(Qo, [Math.cos(h), ...J.axis.map((x) => x * Math.sin(h))]);
      w = ad(P0.w, sc(qd, s));
      dw = ad(P0.dw, sc(qdd, s), cr(P0.w, sc(qd, s)));
    } else if (J.type === 'prismatic') {
      r = ad(r, sc(q, s));
      a = ad(P0.a, cr(P0.dw, r), cr(P0.w, cr(P0.w, r)), sc(qdd, s), sc(2 * qd, cr(P0.w, s)));
    }
    X.push({ Q, p: ad(P0.p, r), w, dw, a, s, J, qdd });
  }
  // backward pass: force f and torque nt (about the link origin) from parent to link
  const f = links.map(() => [0, 0, 0]);
  const nt = links.map(() => [0, 0, 0]);
  for (let i = n - 1; i >= 1; --i) {
    const L = links[i];
    const x = X[i];
    const rc = qr(x.Q, L.com);
    const ac = ad(x.a, cr(x.dw, rc), cr(x.w, cr(x.w, rc)));
    const F = sc(L.mass, ac);
    const [ixx, iyy, izz, ixy, ixz, iyz] = L.inertia;
    const Iw = (v) => { // world inertia about the COM times v: Q I Q^T v
      const u = qr([x.Q[0], -x.Q[1], -x.Q[2], -x.Q[3]], v);
      return qr(x.Q, [ixx * u[0] + ixy * u[1] + ixz * u[2], ixy * u[0] + iyy * u[1] + iyz * u[2], ixz * u[0] + iyz * u[1] + izz * u[2]]);
    };
    const N = ad(Iw(x.dw), cr(x.w, Iw(x.w)));
    f[i] = ad(f[i], F);
    nt[i] = ad(nt[i], N, cr(rc, F));
    const p = L.parent;
    if (p > 0) {
      f[p] = ad(f[p], f[i]);
      nt[p] = ad(nt[p], nt[i], cr(ad(x.p, sc(-1, X[p].p)), f[i]));
    }
  }
  const tau = {};
  for (let i = 1; i < n; ++i) {
    const J = links[i].joint;
    if (J.type === 'fixed') continue;
    tau[J.name] = (J.type === 'revolute' ? dt3(X[i].s, nt[i]) : dt3(X[i].s, f[i])) + (J.armature || 0) * X[i].qdd;
  }
  return tau;
}

// Drive-force readback of a fixed-base run against inverse dynamics at the start of each
// step with qdd = (qd1 - qd0) / dt: any solver gives qd1 = qd* + M^-1 lambda for its drive
// impulses lambda, so tau(start state, qdd) = lambda / dt (no limits, friction or damping).
function rneaCheck(title, doc, got) {
  const names = doc.links.filter((L) => L.joint && L.joint.type !== 'fixed').map((L) => L.joint.name);
  const dtf = f32(doc.dt);
  const errs = names.map(() => 0);
  let scale = 0;
  for (let k = 1; k < got.length; ++k) {
    const m = (arr) => Object.fromEntries(names.map((nm, i) => [nm, arr[i]]));
    const qdd = names.map((_, i) => (got[k].qd[i] - got[k - 1].qd[i]) / dtf);
    const tau = inverseDynamics(doc, m(got[k - 1].q), m(got[k - 1].qd), m(qdd));
    names.forEach((nm, i) => {
      errs[i] = Math.max(errs[i], Math.abs(got[k].f[i] - tau[nm]));
      scale = Math.max(scale, Math.abs(tau[nm]));
    });
  }
  const e = Math.max(...errs);
  check(title, e / scale < 1e-5, `max |f - tau_ID| = ${e.toExponential(2)} (rel ${(e / scale).toExponential(2)} of max |f| ${scale.toFixed(3)}), per joint ${errs.map((x) => x.toExponential(1)).join(' ')}`);
}

async function main() {
  const P = await loadPhysX(__dirname);
  console.log(`PhysX version 0x${P.PHYSICS_VERSION.toString(16)} (WebAssembly, CPU, float32)\n`);
  const tol = 2e-6;
  const pgs = (meff, kp, kd, maxImp) => (x, v, xT, vT) => stepPGS(x, v, meff, kp, kd, xT, vT, maxImp);

  // 1. force drive, PGS 1/1
  compareOneDof('1  slider (m 2.5, kp 400, kd 20, moving target), force drive, PGS 1/1, 100 steps',
    run(P, sliderDoc()), pgs(2.5, 400, 20), tol);
  // 1b. one dof: more iterations change nothing
  compareOneDof('1b slider, force drive, PGS 4/2', run(P, sliderDoc({ solver: { type: 'pgs', position_iterations: 4, velocity_iterations: 2 } })),
    pgs(2.5, 400, 20), tol);
  // 2a. armature: effective mass m + armature
  compareOneDof('2a slider with armature 0.7, PGS 1/1 (f includes armature * qdd)', run(P, sliderDoc({ armature: 0.7 })),
    pgs(2.5 + 0.7, 400, 20), tol);
  // 2b. acceleration drive (cfm_scale 0): force = meff * (kp e + kd edot)
  compareOneDof('2b slider, acceleration drive (kp 160, kd 8), PGS 1/1',
    run(P, sliderDoc({ drive: { type: 'acceleration', stiffness: 160, damping: 8 } })), pgs(2.5, 160 * 2.5, 8 * 2.5), tol);
  // 2c. saturated drive: |impulse| <= max_force * dt with drive_limits_are_forces
  {
    const got = run(P, sliderDoc({ drive: { max_force: 30 } }));
    const maxImp = 30 * f32(DT);
    const sat = got.slice(1).filter((r, k) => Math.abs(stepPGS(got[k].q[0], got[k].qd[0], 2.5, 400, 20, ...targetAt(k + 1)).f) * DT > maxImp).length;
    compareOneDof(`2c slider, max_force 30 N (saturated in ${sat} of 100 steps), PGS 1/1`, got, pgs(2.5, 400, 20, maxImp), tol);
  }
  // 2d. TGS, 4 position iterations (sub-steps), 1 velocity iteration
  compareOneDof('2d slider, force drive, TGS 4/1 vs 4 implicit sub-steps of dt/4',
    run(P, sliderDoc({ solver: { type: 'tgs', position_iterations: 4, velocity_iterations: 1 } })),
    (x, v, xT, vT) => stepTGS(4, x, v, 2.5, 400, 20, xT, vT), tol);

  // 3. revolute joint about a skew axis, full inertia tensor, COM on the axis, gravity on
  {
    const axis = [1, 2, 2].map((x) => x / 3);
    const oq = [Math.cos(0.3), Math.sin(0.3) / Math.sqrt(2), 0, Math.sin(0.3) / Math.sqrt(2)];
    // inertia about the COM, link frame; COM on the axis (1 m along it) so gravity has no torque
    const I = [0.30, 0.25, 0.20, 0.03, -0.02, 0.05];
    const com = axis.map((x) => 1.0 * x);
    const targets = [];
    for (let k = 1; k <= 100; ++k) { const [p, v] = targetAt(k); targets.push({ j1: [p, v] }); }
    const doc = baseScene({
      root: { position: [0.1, 0.2, 0.3], quat: [Math.cos(0.2), 0, Math.sin(0.2), 0] },
      links: [
        link('base', -1, 1, [0, 0, 0], [1, 1, 1, 0, 0, 0]),
        link('rotor', 0, 3.0, com, I, {
          name: 'j1', type: 'revolute', origin: { xyz: [0.2, 0.1, 0], quat: oq }, axis,
          drive: { type: 'force', stiffness: 60, damping: 4, max_force: 1e30,
            target_position: targetAt(0)[0], target_velocity: targetAt(0)[1] },
        }),
      ],
      initial: { q: { j1: 0.1 }, qd: { j1: -0.2 } },
      targets,
    });
    // the joint frame's axis in link coordinates is `axis` (child link frame = joint frame at q = 0)
    const [ixx, iyy, izz, ixy, ixz, iyz] = I;
    const Ia = axis[0] * (ixx * axis[0] + ixy * axis[1] + ixz * axis[2]) +
               axis[1] * (ixy * axis[0] + iyy * axis[1] + iyz * axis[2]) +
               axis[2] * (ixz * axis[0] + iyz * axis[1] + izz * axis[2]);
    compareOneDof(`3  revolute about a skew axis, full inertia tensor (I_axis = ${Ia.toFixed(5)}), gravity on, PGS 1/1`,
      run(P, doc), pgs(Ia, 60, 4), tol);
  }

  // 4. pendulum under gravity: 1 kg, COM 0.5 m from a horizontal axis (y), thin rod inertia
  {
    const m = 1.0, l = 0.5, g = 9.81, Ic = m * (2 * l) * (2 * l) / 12;
    const Ip = Ic + m * l * l;
    const pend = (drive, q0, steps) => baseScene({
      steps,
      links: [
        link('base', -1, 1, [0, 0, 0], [1, 1, 1, 0, 0, 0]),
        link('arm', 0, m, [0, 0, -l], [Ic, Ic, 1e-4, 0, 0, 0], {
          name: 'j1', type: 'revolute', origin: { xyz: [0, 0, 1], quat: [1, 0, 0, 0] }, axis: [0, 1, 0], drive,
        }),
      ],
      initial: { q: { j1: q0 } },
    });
    // 4a free swing from 0.3 rad for 10 s. A 1-dof fixed-base step is semi-implicit Euler:
    //    v1 = v0 - dt m g l sin(q0) / I_pivot,  q1 = q0 + dt v1
    const theta0 = 0.3;
    const got = run(P, pend(null, theta0, 600));
    const dtf = f32(DT);
    const rec = [{ q: got[0].q[0], qd: got[0].qd[0] }];
    let qErrLocal = 0, vErrLocal = 0;
    for (let k = 1; k < got.length; ++k) {
      const st = (q, v) => { const v1 = v - dtf * m * g * l * Math.sin(q) / Ip; return { q: q + dtf * v1, qd: v1 }; };
      rec.push(st(rec[k - 1].q, rec[k - 1].qd));
      const loc = st(got[k - 1].q[0], got[k - 1].qd[0]);
      qErrLocal = Math.max(qErrLocal, Math.abs(loc.q - got[k].q[0]));
      vErrLocal = Math.max(vErrLocal, Math.abs(loc.qd - got[k].qd[0]));
    }
    const qErrFree = Math.max(...got.map((r, k) => Math.abs(r.q[0] - rec[k].q)));
    const E = (r) => 0.5 * Ip * r.qd[0] * r.qd[0] + m * g * l * (1 - Math.cos(r.q[0]));
    const E0 = E(got[0]);
    const dE = Math.max(...got.map((r) => Math.abs(E(r) - E0))) / E0;
    const ups = [];
    for (let k = 1; k < got.length; ++k) {
      const a = got[k - 1].q[0], b = got[k].q[0];
      if (a < 0 && b >= 0) ups.push((k - 1 + a / (a - b)) * DT);
    }
    const period = (ups[ups.length - 1] - ups[0]) / (ups.length - 1);
    const T0 = 2 * Math.PI * Math.sqrt(Ip / (m * g * l));
    const Tth = T0 * (1 + theta0 * theta0 / 16 + 11 * theta0 ** 4 / 3072);
    const amp = Math.max(...got.slice(-120).map((r) => Math.abs(r.q[0])));
    check('4a free pendulum, 10 s, PGS 1/1: semi-implicit Euler recurrence, period, energy',
      qErrLocal < 1e-6 && vErrLocal < 2e-6 && qErrFree < 1e-4 && Math.abs(period - Tth) / Tth < 2e-3 && dE < 0.05 && Math.abs(amp - theta0) < 0.01,
      `per step |q err| ${qErrLocal.toExponential(2)} rad, |qd err| ${vErrLocal.toExponential(2)} rad/s; free run over 600 steps |q err| ${qErrFree.toExponential(2)} rad\n` +
      `       period ${period.toFixed(5)} s vs exact pendulum ${Tth.toFixed(5)} s (rel ${(Math.abs(period - Tth) / Tth).toExponential(2)}); ` +
      `energy oscillates by max ${(100 * dE).toFixed(2)} % (symplectic Euler, no drift); amplitude in the last 2 s ${amp.toFixed(4)} rad`);
    // 4b driven pendulum, target 0.8 rad, settles where the drive balances gravity
    const kp = 50, kd = 5, qT = 0.8;
    const gotD = run(P, pend({ type: 'force', stiffness: kp, damping: kd, max_force: 1e30, target_position: qT, target_velocity: 0 }, 0, 600));
    const last = gotD[gotD.length - 1];
    const q = last.q[0];
    // positive rotation about +y swings the COM (0,0,-l) towards -x: gravity torque about y is -m g l sin q
    const tauG = -m * g * l * Math.sin(q);
    const resid = kp * (qT - q) + tauG;
    check('4b driven pendulum at rest (PGS 1/1): drive torque balances gravity',
      Math.abs(resid) < 1e-3 && Math.abs(last.f[0] + tauG) < 1e-3 && Math.abs(last.qd[0]) < 1e-5,
      `q = ${q.toFixed(6)} rad, qd = ${last.qd[0].toExponential(2)}, f = ${last.f[0].toFixed(6)} Nm, ` +
      `m g l sin q = ${(-tauG).toFixed(6)} Nm, kp (qT - q) - m g l sin q = ${resid.toExponential(2)}`);
  }

  // 5. drive-force readback on a 3-link chain and a floating base (converged PGS)
  const readback = (title, doc) => {
    const got = run(P, doc);
    const names = doc.links.filter((L) => L.joint && L.joint.type !== 'fixed').map((L) => L.joint);
    const errs = names.map(() => 0);
    let scale = 0;
    for (let k = 1; k < got.length; ++k) {
      names.forEach((J, i) => {
        const d = J.drive;
        const want = d.stiffness * (d.target_position - got[k].q[i]) + d.damping * (d.target_velocity - got[k].qd[i]);
        errs[i] = Math.max(errs[i], Math.abs(got[k].f[i] - want));
        scale = Math.max(scale, Math.abs(want));
      });
    }
    const e = Math.max(...errs);
    check(title, e / scale < 1e-5, `max |f - (kp (xT - q1) + kd (vT - qd1))| = ${e.toExponential(2)} (rel ${(e / scale).toExponential(2)} of max |f| ${scale.toFixed(3)}), per joint ${errs.map((x) => x.toExponential(1)).join(' ')}`);
  };
  {
    const drive = (qT) => ({ type: 'force', stiffness: 200, damping: 10, max_force: 1e30, target_position: qT, target_velocity: 0.3 });
    const chain = baseScene({
      steps: 120,
      solver: { type: 'pgs', position_iterations: 1, velocity_iterations: 1 },
      links: [
        link('base', -1, 1, [0, 0, 0], [1, 1, 1, 0, 0, 0]),
        link('l1', 0, 1.2, [0.25, 0, 0], [0.01, 0.03, 0.03, 0, 0, 0], { name: 'j1', type: 'revolute', origin: { xyz: [0, 0, 0.5], quat: [1, 0, 0, 0] }, axis: [0, 1, 0], drive: drive(0.4) }),
        link('l2', 1, 0.8, [0.2, 0.02, 0], [0.005, 0.02, 0.02, 0.001, 0, 0], { name: 'j2', type: 'prismatic', origin: { xyz: [0.5, 0, 0], quat: [1, 0, 0, 0] }, axis: [1, 0, 0], drive: drive(0.1) }),
        link('l3', 2, 0.5, [0.15, 0, 0], [0.002, 0.01, 0.01, 0, 0, 0], { name: 'j3', type: 'revolute', origin: { xyz: [0.4, 0, 0], quat: [Math.SQRT1_2, Math.SQRT1_2, 0, 0] }, axis: [0, 1, 0], drive: drive(-0.5) }),
      ],
      initial: { q: { j1: 0.1, j2: 0.05, j3: 0.2 }, qd: { j1: 1.0, j2: -0.3, j3: 2.0 } },
    });
    rneaCheck('5a readback vs inverse dynamics, 3-link chain (revolute/prismatic/revolute) under gravity, PGS 1/1', chain, run(P, chain));
    const chain8 = JSON.parse(JSON.stringify(chain));
    chain8.solver = { type: 'pgs', position_iterations: 8, velocity_iterations: 2 };
    rneaCheck('5b readback vs inverse dynamics, same chain, PGS 8/2', chain8, run(P, chain8));
    const chainT = JSON.parse(JSON.stringify(chain));
    chainT.solver = { type: 'tgs', position_iterations: 4, velocity_iterations: 1 };
    rneaCheck('5c readback vs inverse dynamics, same chain, TGS 4/1', chainT, run(P, chainT));
    const chainA = JSON.parse(JSON.stringify(chain));
    chainA.links[2].joint.armature = 0.3; chainA.links[3].joint.armature = 0.05;
    rneaCheck('5d readback vs inverse dynamics, same chain with armatures, PGS 1/1', chainA, run(P, chainA));
    const floating = baseScene({
      steps: 120, gravity: [0, 0, 0], floating_base: true,
      solver: { type: 'pgs', position_iterations: 50, velocity_iterations: 1 },
      root: { position: [0, 0, 1], quat: [1, 0, 0, 0], linear_velocity: [0.1, 0, 0], angular_velocity: [0, 0, 0.5] },
      links: [
        link('body', -1, 5, [0.05, 0, 0], [0.1, 0.2, 0.25, 0, 0, 0]),
        link('arm', 0, 1, [0.2, 0, 0], [0.002, 0.02, 0.02, 0, 0, 0], { name: 'j1', type: 'revolute', origin: { xyz: [0.3, 0, 0], quat: [1, 0, 0, 0] }, axis: [0, 0, 1], drive: drive(0.7) }),
      ],
    });
    readback('5e readback, floating base + 1 revolute, no gravity, PGS 50/1', floating);
  }

  // 6. floating single body: COM moves straight (origin-velocity <-> COM-velocity conversion)
  {
    const com = [0.2, -0.1, 0.05];
    const w = [0.3, -0.2, 1.5], v = [0.4, 0.1, -0.2];
    const q0 = [Math.cos(0.4), 0, 0, Math.sin(0.4)];
    const doc = baseScene({
      steps: 60, gravity: [0, 0, 0], floating_base: true,
      root: { position: [1, 2, 3], quat: q0, linear_velocity: v, angular_velocity: w },
      links: [link('body', -1, 2, com, [0.1, 0.12, 0.15, 0.01, 0, 0])],
    });
    const got = run(P, doc);
    const comW = (r) => {
      const p = r.root.slice(0, 3), qq = r.root.slice(3, 7);
      return H.qrot(qq, com).map((x, i) => x + p[i]);
    };
    const vCom0 = v.map((x, i) => x + [w[1] * H.qrot(q0, com)[2] - w[2] * H.qrot(q0, com)[1],
      w[2] * H.qrot(q0, com)[0] - w[0] * H.qrot(q0, com)[2],
      w[0] * H.qrot(q0, com)[1] - w[1] * H.qrot(q0, com)[0]][i]);
    let err = 0;
    const c0 = comW(got[0]);
    got.forEach((r, k) => {
      const c = comW(r);
      for (let i = 0; i < 3; ++i) err = Math.max(err, Math.abs(c[i] - (c0[i] + k * DT * vCom0[i])));
    });
    const r0 = got[0].root;
    const vErr = Math.max(...[0, 1, 2].map((i) => Math.abs(r0[10 + i] - v[i])));
    check('6  floating single body: COM straight line, root velocity round trip', err < 1e-5 && vErr < 1e-6,
      `max COM deviation ${err.toExponential(2)} m over 1 s, initial root origin velocity error ${vErr.toExponential(2)} m/s`);
  }

  console.log(failures ? `\n${failures} check(s) FAILED` : '\nall checks passed');
  return failures ? 1 : 0;
}

main().then((c) => { process.exitCode = c; }, (e) => { console.error(e && e.stack ? e.stack : e); process.exitCode = 1; });
