// Reference numbers for ground contact measured in PhysX 5.6.1 itself (physx-js-webidl@2.7.3,
// PhysX compiled to WebAssembly): the cases of issue 34 that featherdrive's contact rows must
// reproduce. docs/math/contact.md, "Reference numbers", shows the command and its output.
//
//   node bench/physx_contact_reference.js [HARNESS_DIR] [key=value ...]
//
// HARNESS_DIR (or the environment variable FEATHERDRIVE_PHYSX_DIR; default build/physx) is a
// folder that tests/physx/install.sh installed into: physx_loader.js and node_modules/.
// Options (defaults in brackets):
//   case=a,b,c,d,e     which cases [all]          solver=pgs,tgs   which solvers [both]
//   iterations=P/V     position/velocity iterations of every body and the articulation [4/1]
//   dt=S [0.01]  mu=M (static = dynamic friction of every material) [0.5 boxes, 1 quadruped]
//   restitution=E [0.5, case c]   bounce=V  the scene's bounce threshold [PhysX's 2 m/s]
//   contact_offset=C [0.02]  rest_offset=R [0]   (of every shape, the plane's included)
//   kp=K kd=D [300, 10: the quadruped's drives]   seconds=T [2: how long d and e run]
//   impulses=0 hides case a's per-contact impulses   trace=1 prints d and e every 0.1 s
//   body=link|rigid    cases a-c: the body is a one-link floating articulation [link] or a
//                      PxRigidDynamic (solved by PhysX's island solver, not the articulation's)
// The cases, z up, gravity 9.81 m/s^2, ground plane z = 0 (PxCreatePlane):
//   a  1 kg box (0.2 m cube) resting: sum of normal impulses / (dt m g) after 100 steps and over
//      the next 1000, and the drift of z over those 1000 steps
//   b  the box sliding at v0 = 2 m/s: stopping distance against v0^2 / (2 mu g) and against the
//      same law stepped by semi-implicit Euler (what a discrete solver can match exactly)
//   c  1 kg sphere (r = 0.1 m) dropped from 0.2 m (its lowest point): rebound speed and apex,
//      with the scene's bounce threshold and with threshold 0.5 m/s (one that lets it bounce)
//   d  a quadruped articulation (box base, 4 legs of two capsules, hip and knee revolute joints
//      about y under PD drives) standing: base height, joint positions and foot impulses at 2 s
//   e  the quadruped dropped from 0.2 m
// Output: CSV lines `case,solver,quantity,value,reference` (reference: the closed form where
// there is one, else empty) after a `#` line naming the settings. Impulses are those PhysX reports
// per contact point (PxContactPairPoint::impulse, through a simulation event callback): normal
// impulses only; the bindings expose no friction impulses.
'use strict';
const path = require('path');

const G = 9.81;

function parseOptions(argv) {
  const o = {
    dir: process.env.FEATHERDRIVE_PHYSX_DIR || 'build/physx', cases: 'abcde'.split(''),
    solvers: ['pgs', 'tgs'], pos: 4, vel: 1, dt: 0.01, mu: null, restitution: 0.5, bounce: null,
    contactOffset: 0.02, restOffset: 0, kp: 300, kd: 10, impulses: true, seconds: 2, trace: false,
    body: 'link',
  };
  for (const a of argv) {
    const eq = a.indexOf('=');
    if (eq < 0) { o.dir = a; continue; }
    const k = a.slice(0, eq), v = a.slice(eq + 1);
    const number = () => {
      const x = Number(v);
      if (v === '' || !Number.isFinite(x)) throw new Error(`option ${k}: not a number: "${v}"`);
      return x;
    };
    if (k === 'case') {
      o.cases = v.split(',');
      for (const c of o.cases) if (!'abcde'.includes(c) || c.length !== 1) throw new Error(`option case: unknown case "${c}" (a, b, c, d, e)`);
    } else if (k === 'solver') {
      o.solvers = v.split(',');
      for (const s of o.solvers) if (s !== 'pgs' && s !== 'tgs') throw new Error(`option solver: unknown solver "${s}" (pgs, tgs)`);
    } else if (k === 'iterations') {
      const m = /^(\d+)\/(\d+)$/.exec(v);
      if (!m || +m[1] < 1 || +m[1] > 255 || +m[2] > 255) throw new Error(`option iterations: want P/V with 1 <= P <= 255, 0 <= V <= 255, got "${v}"`);
      o.pos = +m[1]; o.vel = +m[2];
    } else if (k === 'dt') { o.dt = number(); if (!(o.dt > 0)) throw new Error(`option dt: must be > 0, got ${v}`); }
    else if (k === 'mu') { o.mu = number(); if (o.mu < 0) throw new Error(`option mu: must be >= 0, got ${v}`); }
    else if (k === 'restitution') { o.restitution = number(); if (o.restitution < 0 || o.restitution > 1) throw new Error(`option restitution: must be in [0, 1], got ${v}`); }
    else if (k === 'bounce') { o.bounce = number(); if (!(o.bounce > 0)) throw new Error(`option bounce: must be > 0, got ${v}`); }
    else if (k === 'contact_offset') { o.contactOffset = number(); }
    else if (k === 'rest_offset') { o.restOffset = number(); }
    else if (k === 'kp') { o.kp = number(); }
    else if (k === 'kd') { o.kd = number(); }
    else if (k === 'impulses') { o.impulses = v !== '0'; }
    else if (k === 'seconds') { o.seconds = number(); if (!(o.seconds > 0)) throw new Error(`option seconds: must be > 0, got ${v}`); }
    else if (k === 'trace') { o.trace = v !== '0'; }
    else if (k === 'body') { if (v !== 'link' && v !== 'rigid') throw new Error(`option body: want link or rigid, got "${v}"`); o.body = v; }
    else throw new Error(`unknown option "${k}"`);
  }
  if (!(o.restOffset < o.contactOffset)) throw new Error(`options: rest_offset (${o.restOffset}) must be below contact_offset (${o.contactOffset})`);
  return o;
}

function out(...cols) {
  console.log(cols.map((c) => (typeof c === 'number' ? fmt(c) : c)).join(','));
}
function fmt(x) { return Number.isInteger(x) ? String(x) : x.toPrecision(9); }

// One PhysX world for the process; a scene per run.
function makeWorld(P) {
  const allocator = new P.PxDefaultAllocator();
  const errors = [];
  const errorCallback = new P.PxErrorCallbackImpl();
  errorCallback.reportError = (code, message) => {
    if (code !== P.PxErrorCodeEnum.eDEBUG_INFO && code !== P.PxErrorCodeEnum.eDEBUG_WARNING &&
        code !== P.PxErrorCodeEnum.ePERF_WARNING) errors.push(`PhysX error ${code}: ${P.UTF8ToString ? P.UTF8ToString(message) : message}`);
  };
  const foundation = P.CreateFoundation(P.PHYSICS_VERSION, allocator, errorCallback);
  const tolerances = new P.PxTolerancesScale();
  const physics = P.CreatePhysics(P.PHYSICS_VERSION, foundation, tolerances);
  const dispatcher = P.DefaultCpuDispatcherCreate(0);
  return { P, physics, tolerances, dispatcher, errors, allocator, errorCallback, foundation };
}

// A scene with gravity -z, the ground plane z = 0 and contact reports for every touching pair.
// PhysX's default filter shader solves contacts but reports none; the pass-through shader of the
// bindings lets us ask for the contact points (and their impulses) as well.
function makeScene(W, o, solver, mu, restitution, bounce) {
  const { P, physics } = W;
  const sd = new P.PxSceneDesc(W.tolerances);
  sd.gravity = new P.PxVec3(0, 0, -G);
  sd.cpuDispatcher = W.dispatcher;
  sd.solverType = solver === 'tgs' ? P.PxSolverTypeEnum.eTGS : P.PxSolverTypeEnum.ePGS;
  if (bounce !== null) sd.bounceThresholdVelocity = bounce;
  const F = P.PxPairFlagEnum;
  const pairFlags = F.eSOLVE_CONTACT | F.eDETECT_DISCRETE_CONTACT | F.eNOTIFY_TOUCH_FOUND |
                    F.eNOTIFY_TOUCH_PERSISTS | F.eNOTIFY_CONTACT_POINTS;
  const shader = new P.PassThroughFilterShaderImpl();
  shader.filterShader = function filterShader() { this.outputPairFlags = pairFlags; return 0; };
  P.setupPassThroughFilterShader(sd, shader);
  const contacts = [];  // filled by onContact during fetchResults: {shapes: [ptr0, ptr1], points}
  const buffer = new P.PxArray_PxContactPairPoint(64);
  const cb = new P.PxSimulationEventCallbackImpl();
  cb.onContact = (headerPtr, pairsPtr, nbPairs) => {
    const first = P.wrapPointer(pairsPtr, P.PxContactPair);
    for (let i = 0; i < nbPairs; ++i) {
      const pair = P.NativeArrayHelpers.prototype.getContactPairAt(first, i);
      const n = pair.extractContacts(buffer.begin(), 64);
      const points = [];
      for (let c = 0; c < n; ++c) {
        const pt = buffer.get(c);
        const nrm = [pt.normal.x, pt.normal.y, pt.normal.z];
        const imp = [pt.impulse.x, pt.impulse.y, pt.impulse.z];
        points.push({ p: [pt.position.x, pt.position.y, pt.position.z], sep: pt.separation, n: nrm, imp });
      }
      contacts.push({ shapes: [P.getPointer(pair.get_shapes(0)), P.getPointer(pair.get_shapes(1))], points });
    }
  };
  cb.onConstraintBreak = () => {}; cb.onWake = () => {}; cb.onSleep = () => {}; cb.onTrigger = () => {};
  sd.simulationEventCallback = cb;
  const scene = physics.createScene(sd);
  if (!scene) throw new Error('PhysX could not create the scene');
  const material = physics.createMaterial(mu, mu, restitution);
  const plane = P.CreatePlane(physics, new P.PxPlane(0, 0, 1, 0), material);
  const planeShape = shapesOf(P, plane)[0];
  planeShape.setContactOffset(o.contactOffset);
  planeShape.setRestOffset(o.restOffset);
  scene.addActor(plane);
  return { scene, material, contacts, keep: [shader, cb, buffer, plane] };
}

function shapesOf(P, actor) {
  const n = actor.getNbShapes();
  const buf = new P.PxArray_PxShapePtr(n);
  actor.getShapes(buf.begin(), n, 0);
  const res = [];
  for (let i = 0; i < n; ++i) res.push(buf.get(i));
  return res;
}

function addShape(W, o, actor, geometry, material, localPose) {
  const { P, physics } = W;
  const shape = physics.createShape(geometry, material, true);
  shape.setContactOffset(o.contactOffset);
  shape.setRestOffset(o.restOffset);
  if (localPose) shape.setLocalPose(localPose);
  actor.attachShape(shape);
  return shape;
}

const tf = (P, p, q) => new P.PxTransform(new P.PxVec3(p[0], p[1], p[2]), new P.PxQuat(q[1], q[2], q[3], q[0]));
const QI = [1, 0, 0, 0];
const S = Math.SQRT1_2;
const Q_X_TO_Z = [S, 0, -S, 0];  // about y by -90 deg: a capsule's x axis onto z
const Q_X_TO_Y = [S, 0, 0, S];   // about z by +90 deg: a joint's twist axis x onto y

// Sum over the step's reports of the impulse along each contact normal, and the tangential part.
function impulseTotals(contacts, filter) {
  let normal = 0, tangent = [0, 0, 0], count = 0;
  for (const c of contacts) {
    if (filter && !filter(c)) continue;
    for (const pt of c.points) {
      const jn = pt.imp[0] * pt.n[0] + pt.imp[1] * pt.n[1] + pt.imp[2] * pt.n[2];
      normal += jn;
      for (let k = 0; k < 3; ++k) tangent[k] += pt.imp[k] - jn * pt.n[k];
      count += 1;
    }
  }
  return { normal, tangent: Math.hypot(...tangent), count };
}

// The box or sphere of cases a-c: by default the one link of a floating-base articulation (the
// path featherdrive's robots take: the contact rows are solved in the articulation's own sweep),
// with body=rigid a PxRigidDynamic (PhysX's island solver). Returns {body, setVelocity}.
function freeBody(W, o, run, geometry, mass, inertia, pose) {
  const { P, physics } = W;
  let body, art = null;
  if (o.body === 'link') {
    art = physics.createArticulationReducedCoordinate();
    art.setSolverIterationCounts(o.pos, o.vel);
    art.setSleepThreshold(0);
    art.setStabilizationThreshold(0);
    body = art.createLink(null, tf(P, pose, QI));
  } else {
    body = physics.createRigidDynamic(tf(P, pose, QI));
    body.setSolverIterationCounts(o.pos, o.vel);
    body.setSleepThreshold(0);
  }
  addShape(W, o, body, geometry, run.material);
  body.setMass(mass);
  body.setMassSpaceInertiaTensor(new P.PxVec3(...inertia));
  body.setLinearDamping(0);
  body.setAngularDamping(0);
  if (art) { run.scene.addArticulation(art); art.setWakeCounter(1e9); } else { run.scene.addActor(body); body.setWakeCounter(1e9); }
  const setVelocity = (v) => (art ? art.setRootLinearVelocity(new P.PxVec3(...v))
                                  : body.setLinearVelocity(new P.PxVec3(...v)));
  return { body, setVelocity };
}

function step(W, run, dt) {
  run.contacts.length = 0;
  run.scene.simulate(dt);
  run.scene.fetchResults(true);
  if (W.errors.length) throw new Error(W.errors.join('; '));
}

// (a) A 1 kg box (0.2 m cube) placed touching the ground.
function caseA(W, o, solver) {
  const { P } = W;
  const mu = o.mu === null ? 0.5 : o.mu;
  const run = makeScene(W, o, solver, mu, 0, o.bounce);
  const h = 0.1, m = 1, I = m * (2 * 0.2 * 0.2) / 12;
  const { body: box } = freeBody(W, o, run, new P.PxBoxGeometry(h, h, h), m, [I, I, I], [0, 0, h]);
  for (let k = 0; k < 100; ++k) step(W, run, o.dt);
  const z0 = box.getGlobalPose().p.z;
  let lo = Infinity, hi = -Infinity, sum = 0, pts = 0, zlo = Infinity, zhi = -Infinity;
  for (let k = 0; k < 1000; ++k) {
    step(W, run, o.dt);
    const r = impulseTotals(run.contacts).normal / (o.dt * m * G);
    lo = Math.min(lo, r); hi = Math.max(hi, r); sum += r;
    pts = impulseTotals(run.contacts).count;
    const z = box.getGlobalPose().p.z;
    zlo = Math.min(zlo, z); zhi = Math.max(zhi, z);
  }
  const z1 = box.getGlobalPose().p.z;
  out('a', solver, 'contact_points', pts, 4);
  out('a', solver, 'z_after_100_steps-h', z0 - h, 0);
  out('a', solver, 'sum_jn/(dt_m_g)_mean_1000', sum / 1000, 1);
  out('a', solver, 'sum_jn/(dt_m_g)_min_1000', lo, 1);
  out('a', solver, 'sum_jn/(dt_m_g)_max_1000', hi, 1);
  out('a', solver, 'z_drift_1000', z1 - z0, 0);
  out('a', solver, 'z_range_1000', zhi - zlo, 0);
  out('a', solver, 'vz_end', box.getLinearVelocity().z, 0);
  if (o.impulses) {
    // The last step's contact points as reported (PxContactPairPoint): impulse along the normal
    // and the separation, one line each; their sum is m g dt.
    let i = 0;
    for (const c of run.contacts) {
      for (const pt of c.points) {
        const jn = pt.imp[0] * pt.n[0] + pt.imp[1] * pt.n[1] + pt.imp[2] * pt.n[2];
        out('a', solver, `point${i}:(${pt.p.map((x) => x.toFixed(3)).join(' ')}):jn/(dt_m_g)`, jn / (o.dt * m * G), 0.25);
        out('a', solver, `point${i}:separation`, pt.sep, '');
        i += 1;
      }
    }
  }
}

// (b) The box sliding along x at v0 = 2 m/s from touching the ground.
function caseB(W, o, solver) {
  const { P } = W;
  const mu = o.mu === null ? 0.5 : o.mu;
  const run = makeScene(W, o, solver, mu, 0, o.bounce);
  const h = 0.1, m = 1, I = m * (2 * 0.2 * 0.2) / 12, v0 = 2;
  const { body: box, setVelocity } = freeBody(W, o, run, new P.PxBoxGeometry(h, h, h), m, [I, I, I], [0, 0, h]);
  setVelocity([v0, 0, 0]);
  const x0 = box.getGlobalPose().p.x;
  const a = mu * G, closed = v0 * v0 / (2 * a);
  // Semi-implicit Euler (the velocity first, then the position with it) stops after N = floor(v0 /
  // (a dt)) full steps of deceleration a and one step that brings v to 0 in place:
  // d = dt (N v0 - a dt N (N + 1) / 2).
  const N = Math.floor(v0 / (a * o.dt) + 1e-12);
  const discrete = o.dt * (N * v0 - a * o.dt * N * (N + 1) / 2);
  const vs = [];
  let k = 0;
  for (; k < 100000; ++k) {
    step(W, run, o.dt);
    vs.push(box.getLinearVelocity().x);
    if (box.getLinearVelocity().x <= 1e-9) break;
  }
  const x1 = box.getGlobalPose().p.x;
  out('b', solver, 'steps_to_stop', k + 1, N + 1);
  out('b', solver, 'decel_step1/(mu_g)', (v0 - vs[0]) / o.dt / a, 1);
  out('b', solver, 'decel_step2/(mu_g)', (vs[0] - vs[1]) / o.dt / a, 1);
  out('b', solver, 'stopping_distance_vs_v0^2/(2_mu_g)', x1 - x0, closed);
  out('b', solver, 'relative_error_vs_v0^2/(2_mu_g)', (x1 - x0 - closed) / closed, 0);
  out('b', solver, 'stopping_distance_vs_discrete', x1 - x0, discrete);
  out('b', solver, 'relative_error_vs_discrete', (x1 - x0 - discrete) / discrete, 0);
  for (let j = 0; j < 20; ++j) step(W, run, o.dt);
  out('b', solver, 'x_drift_20_steps_after_stop', box.getGlobalPose().p.x - x1, 0);
}

// (c) A 1 kg sphere (r = 0.1 m) released with its lowest point 0.2 m above the ground.
function caseC(W, o, solver) {
  const { P } = W;
  const mu = o.mu === null ? 0.5 : o.mu;
  const r = 0.1, m = 1, I = 0.4 * m * r * r, drop = 0.2;
  const vImpact = Math.sqrt(2 * G * drop);
  for (const bounce of [o.bounce, 0.5]) {
    const run = makeScene(W, o, solver, mu, o.restitution, bounce);
    const label = bounce === null ? 'default' : String(bounce);
    const { body: ball } = freeBody(W, o, run, new P.PxSphereGeometry(r), m, [I, I, I], [0, 0, r + drop]);
    let vPrev = 0, vApproach = 0, vUp = 0, zTop = -Infinity, touched = false, left = false, kTouch = -1;
    for (let k = 0; k < Math.round(1.5 / o.dt); ++k) {
      step(W, run, o.dt);
      const v = ball.getLinearVelocity().z, z = ball.getGlobalPose().p.z - r;
      if (!touched && run.contacts.length && impulseTotals(run.contacts).normal > 0) {
        touched = true; kTouch = k; vApproach = -(vPrev - G * o.dt);  // what the contact saw
      }
      vPrev = v;
      if (touched) vUp = Math.max(vUp, v);
      if (touched && v > 0) left = true;
      if (left) zTop = Math.max(zTop, z);
    }
    // The discrete fall (semi-implicit Euler) has fallen g dt^2 k (k + 1) / 2 after k steps: it
    // reaches the ground in the first step k where that passes h, at the speed g dt k
    // (sqrt(2 g h) is the continuous one).
    let kc = 1;
    while (G * o.dt * o.dt * kc * (kc + 1) / 2 < drop) kc += 1;
    out('c', solver, `bounce_threshold_${label}:approach_speed_at_contact`, vApproach, G * o.dt * kc);
    out('c', solver, `bounce_threshold_${label}:sqrt(2gh)`, vImpact, '');
    out('c', solver, `bounce_threshold_${label}:first_impulse_step`, kTouch + 1, kc);
    out('c', solver, `bounce_threshold_${label}:rebound_speed`, vUp,
        vApproach < (bounce === null ? 2 : bounce) ? 0 : o.restitution * vApproach);
    out('c', solver, `bounce_threshold_${label}:rebound_apex`, left ? zTop : 0,
        vApproach < (bounce === null ? 2 : bounce) ? 0 : (o.restitution * vApproach) ** 2 / (2 * G));
    out('c', solver, `bounce_threshold_${label}:z_at_1.5s`, ball.getGlobalPose().p.z - r, 0);
  }
}

// (d, e) The quadruped. Base: 0.4 x 0.2 x 0.1 m box, 4 kg, its COM the base frame's origin.
// Legs at (+-0.15, +-0.12, -0.05): hip revolute about y, thigh (0.5 kg) a capsule r = 0.025 with a
// 0.2 m segment from the hip down, knee revolute about y at the segment's end, shin (0.3 kg) the
// same capsule. Link frames at the joints; thigh and shin COMs 0.1 m down their axes; inertias of
// solid cylinders (r 0.025, length 0.2). Drive targets: hip 0.5, knee -1.0 rad, the initial
// pose too, which puts each foot straight below its hip. Positive rotation about +y swings a
// leg's lower end toward -x.
const QUAD = {
  base: { half: [0.2, 0.1, 0.05], mass: 4 },
  thigh: { mass: 0.5, len: 0.2, r: 0.025 }, shin: { mass: 0.3, len: 0.2, r: 0.025 },
  hips: [[0.15, 0.12, -0.05], [0.15, -0.12, -0.05], [-0.15, 0.12, -0.05], [-0.15, -0.12, -0.05]],
  names: ['fl', 'fr', 'hl', 'hr'], hip: 0.5, knee: -1.0,
};
function quadStandingHeight() {
  const { thigh, shin, hip, knee } = QUAD;
  return -QUAD.hips[0][2] + thigh.len * Math.cos(hip) + shin.len * Math.cos(hip + knee) + shin.r;
}
function quadruped(W, o, run, lift) {
  const { P, physics } = W;
  const art = physics.createArticulationReducedCoordinate();
  art.setArticulationFlag(P.PxArticulationFlagEnum.eDISABLE_SELF_COLLISION, true);
  art.setSolverIterationCounts(o.pos, o.vel);
  art.setSleepThreshold(0);
  art.setStabilizationThreshold(0);
  const z0 = quadStandingHeight() + lift;
  const base = art.createLink(null, tf(P, [0, 0, z0], QI));
  const b = QUAD.base;
  addShape(W, o, base, new P.PxBoxGeometry(...b.half), run.material);
  base.setMass(b.mass);
  const h = b.half;
  base.setMassSpaceInertiaTensor(new P.PxVec3(b.mass / 3 * (h[1] ** 2 + h[2] ** 2), b.mass / 3 * (h[0] ** 2 + h[2] ** 2), b.mass / 3 * (h[0] ** 2 + h[1] ** 2)));
  const links = [base], joints = [], feet = new Map(), masses = [b.mass];
  const cyl = (m, r, L) => [m * (3 * r * r + L * L) / 12, m * (3 * r * r + L * L) / 12, m * r * r / 2];
  QUAD.hips.forEach((hp, i) => {
    let parent = base, parentPose = hp;
    for (const [part, spec, q] of [['hip', QUAD.thigh, QUAD.hip], ['knee', QUAD.shin, QUAD.knee]]) {
      const link = art.createLink(parent, tf(P, [hp[0], hp[1], z0 + hp[2]], QI));  // poses set by the joint positions below
      const shape = addShape(W, o, link, new P.PxCapsuleGeometry(spec.r, spec.len / 2), run.material,
                             tf(P, [0, 0, -spec.len / 2], Q_X_TO_Z));
      link.setMass(spec.mass);
      link.setCMassLocalPose(tf(P, [0, 0, -spec.len / 2], QI));
      link.setMassSpaceInertiaTensor(new P.PxVec3(...cyl(spec.mass, spec.r, spec.len)));
      masses.push(spec.mass);
      const j = link.getInboundJoint();
      j.setJointType(P.PxArticulationJointTypeEnum.eREVOLUTE);
      j.setMotion(P.PxArticulationAxisEnum.eTWIST, P.PxArticulationMotionEnum.eFREE);
      j.setParentPose(tf(P, parentPose, Q_X_TO_Y));
      j.setChildPose(tf(P, [0, 0, 0], Q_X_TO_Y));
      j.setDriveParams(P.PxArticulationAxisEnum.eTWIST,
                       new P.PxArticulationDrive(o.kp, o.kd, 1e30, P.PxArticulationDriveTypeEnum.eFORCE));
      j.setDriveTarget(P.PxArticulationAxisEnum.eTWIST, q);
      j.setDriveVelocity(P.PxArticulationAxisEnum.eTWIST, 0);
      joints.push({ name: `${QUAD.names[i]}_${part}`, px: j, target: q });
      links.push(link);
      if (part === 'knee') feet.set(P.getPointer(shape), QUAD.names[i]);
      parent = link; parentPose = [0, 0, -spec.len];
    }
  });
  for (const l of links) { l.setLinearDamping(0); l.setAngularDamping(0); }
  run.scene.addArticulation(art);
  for (const j of joints) { j.px.setJointPosition(P.PxArticulationAxisEnum.eTWIST, j.target); j.px.setJointVelocity(P.PxArticulationAxisEnum.eTWIST, 0); }
  art.setRootGlobalPose(tf(P, [0, 0, z0], QI));
  const KF = P.PxArticulationKinematicFlagEnum;
  art.updateKinematic(new P.PxArticulationKinematicFlags(KF.ePOSITION | KF.eVELOCITY));
  art.wakeUp();
  art.setWakeCounter(1e9);
  return { art, base, links, joints, feet, z0, mass: masses.reduce((a, x) => a + x, 0) };
}

function caseQuad(W, o, solver, which) {
  const mu = o.mu === null ? 1 : o.mu;
  const run = makeScene(W, o, solver, mu, 0, o.bounce);
  const lift = which === 'e' ? 0.2 : 0;
  const Q = quadruped(W, o, run, lift);
  const steps = Math.round(o.seconds / o.dt);
  let minZ = Infinity, maxPen = 0, perFoot = null;
  for (let k = 0; k < steps; ++k) {
    step(W, run, o.dt);
    minZ = Math.min(minZ, Q.base.getGlobalPose().p.z);
    if (o.trace && (k + 1) % Math.max(1, Math.round(0.1 / o.dt)) === 0) {
      out(which, solver, `trace:t=${((k + 1) * o.dt).toFixed(2)}:base_z,x,vz`, Q.base.getGlobalPose().p.z,
          `${Q.base.getGlobalPose().p.x},${Q.base.getLinearVelocity().z}`);
    }
    for (const c of run.contacts) for (const pt of c.points) maxPen = Math.min(maxPen, pt.sep);
    if (k === steps - 1) {
      perFoot = new Map(QUAD.names.map((n) => [n, 0]));
      let other = 0;
      for (const c of run.contacts) {
        const foot = Q.feet.get(c.shapes[0]) || Q.feet.get(c.shapes[1]);
        const jn = impulseTotals([c]).normal;
        if (foot) perFoot.set(foot, perFoot.get(foot) + jn); else other += jn;
      }
      perFoot.set('other', other);
    }
  }
  const pose = Q.base.getGlobalPose();
  out(which, solver, 'base_z_initial', Q.z0, '');
  out(which, solver, 'base_z_at_end', pose.p.z, '');
  out(which, solver, 'base_z_min', minZ, '');
  out(which, solver, 'base_tilt_at_end(1-qw^2)', 1 - pose.q.w * pose.q.w, 0);
  out(which, solver, 'base_x_at_end', pose.p.x, '');
  out(which, solver, 'base_vz_at_end', Q.base.getLinearVelocity().z, 0);
  for (const j of Q.joints) out(which, solver, `q:${j.name}`, j.px.getJointPosition(W.P.PxArticulationAxisEnum.eTWIST), j.target);
  let total = 0;
  for (const [foot, jn] of perFoot) {
    out(which, solver, `foot_jn/(dt_M_g):${foot}`, jn / (o.dt * Q.mass * G), foot === 'other' ? 0 : '');
    total += jn;
  }
  out(which, solver, 'sum_jn/(dt_M_g)_last_step', total / (o.dt * Q.mass * G), 1);
  out(which, solver, 'deepest_separation', maxPen, -o.restOffset);
}

async function main() {
  const o = parseOptions(process.argv.slice(2));
  const dir = path.resolve(o.dir);
  let loader;
  try { loader = require(path.join(dir, 'physx_loader.js')); } catch (e) {
    throw new Error(`no PhysX harness in ${dir} (run tests/physx/install.sh ${o.dir}, or name the folder as the first argument or in FEATHERDRIVE_PHYSX_DIR)`);
  }
  const P = await loader.loadPhysX(dir);
  const W = makeWorld(P);
  console.log(`# PhysX ${P.PHYSICS_VERSION >> 24}.${(P.PHYSICS_VERSION >> 16) & 255}.${(P.PHYSICS_VERSION >> 8) & 255} (physx-js-webidl); dt ${o.dt}, iterations ${o.pos}/${o.vel}, contact offset ${o.contactOffset}, rest offset ${o.restOffset}, cases a-c body ${o.body}, bounce threshold ${o.bounce === null ? 'default (2 m/s)' : o.bounce}`);
  console.log('case,solver,quantity,value,reference');
  for (const c of o.cases) {
    for (const solver of o.solvers) {
      if (c === 'a') caseA(W, o, solver);
      else if (c === 'b') caseB(W, o, solver);
      else if (c === 'c') caseC(W, o, solver);
      else caseQuad(W, o, solver, c);
    }
  }
}

main().catch((e) => { console.error(`physx_contact_reference.js: ${e.message}`); process.exitCode = 2; });
