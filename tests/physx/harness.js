#!/usr/bin/env node
'use strict';
// featherdrive <-> PhysX comparison harness.
//
//   node harness.js SCENE.json OUT.csv
//   node harness.js --serve SOCKET [IDLE_SECONDS]     (runs many, PhysX loaded once)
//
// Builds the articulation described by SCENE.json (format "featherdrive-physx/2", see
// README.md) in PhysX 5.6.1 (WebAssembly build, CPU solver, float32), with its collision shapes
// and a ground plane when the scene has them, steps it and writes the joint trajectory, the
// per-step drive forces and the per-link contact forces as CSV.
//
// Exit status: 0 success, 2 bad input (unreadable/invalid scene, or PhysX rejected a
// parameter while the scene was built), 1 any other failure (PhysX error while stepping,
// articulation asleep at the end, non-finite state, I/O error).

const fs = require('fs');
const path = require('path');
const { loadPhysX } = require('./physx_loader.js');

// /2 added shapes, the ground and contact options (a /1 scene is a /2 scene without them).
const FORMAT = 'featherdrive-physx/2';
// PhysX rejects max link velocities above 1e16 (it stores their squares in float32).
const PHYSX_MAX_LINK_VELOCITY = 1e16;
const HUGE = 1e30;
// PxArticulationJointType::eREVOLUTE_UNWRAPPED = 3 exists in PhysX 5.6.1 but the
// WebIDL binding's enum leaves it out; the wrapper passes enum values through as ints.
const JOINT_TYPE_REVOLUTE_UNWRAPPED = 3;
// A spherical joint's axes (eTWIST, eSWING1, eSWING2 about its joint frame's x, y, z): their
// columns and their names in initial / targets are `<joint>:<axis>`.
const SPHERICAL_AXES = ['twist', 'swing1', 'swing2'];
// PhysX 5.6.1's scene default (PxSceneDesc: 0.2 x PxTolerancesScale::speed) and shape default
// (0.02 x PxTolerancesScale::length): docs/math/contact.md, section 8.
const DEFAULT_BOUNCE_THRESHOLD = 2;
const DEFAULT_CONTACT_OFFSET = 0.02;
// about y by -90 degrees: PhysX's capsule lies along its shape frame's x, the scene's along z.
const Q_CAPSULE_X_TO_Z = [Math.SQRT1_2, 0, -Math.SQRT1_2, 0];

class InputError extends Error {}

// ---------------------------------------------------------------------------------------
// small double-precision math helpers (quaternions are [w, x, y, z])

function qmul(a, b) {
  return [
    a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
    a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
    a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
    a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
  ];
}
function qconj(q) { return [q[0], -q[1], -q[2], -q[3]]; }
function qrot(q, v) {
  const r = qmul(qmul(q, [0, v[0], v[1], v[2]]), qconj(q));
  return [r[1], r[2], r[3]];
}
function qnormalize(q) {
  const n = Math.hypot(q[0], q[1], q[2], q[3]);
  return [q[0] / n, q[1] / n, q[2] / n, q[3] / n];
}
function cross(a, b) {
  return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
}
function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
function add(a, b) { return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]; }
function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }

// Pose = {p: [3], q: [4]}; compose(A, B) = A * B
function compose(A, B) { return { p: add(A.p, qrot(A.q, B.p)), q: qnormalize(qmul(A.q, B.q)) }; }

// Rotation taking the x axis onto unit vector a (shortest arc).
function rotationXTo(a) {
  const d = a[0]; // x . a
  if (d < -1 + 1e-12) return [0, 0, 0, 1]; // 180 degrees about z
  // q = [1 + x.a, x cross a] normalised
  return qnormalize([1 + d, 0, -a[2], a[1]]);
}

// Quaternion [w,x,y,z] of a proper rotation matrix given as rows m[i][j].
function quatFromMatrix(m) {
  const tr = m[0][0] + m[1][1] + m[2][2];
  let q;
  if (tr > 0) {
    const s = Math.sqrt(tr + 1) * 2;
    q = [0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s];
  } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
    const s = Math.sqrt(1 + m[0][0] - m[1][1] - m[2][2]) * 2;
    q = [(m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s];
  } else if (m[1][1] > m[2][2]) {
    const s = Math.sqrt(1 + m[1][1] - m[0][0] - m[2][2]) * 2;
    q = [(m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s];
  } else {
    const s = Math.sqrt(1 + m[2][2] - m[0][0] - m[1][1]) * 2;
    q = [(m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s];
  }
  return qnormalize(q);
}

// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations.
// Returns {values: [3], vectors: V} with A = V diag(values) V^T, V's columns the
// eigenvectors, det(V) = +1.
function symmetricEigen3(A) {
  const a = A.map((r) => r.slice());
  const V = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
  for (let sweep = 0; sweep < 64; ++sweep) {
    const off = Math.abs(a[0][1]) + Math.abs(a[0][2]) + Math.abs(a[1][2]);
    const scale = Math.abs(a[0][0]) + Math.abs(a[1][1]) + Math.abs(a[2][2]);
    if (off === 0 || off <= 1e-300 || off < 1e-17 * scale) break;
    for (const [p, q] of [[0, 1], [0, 2], [1, 2]]) {
      if (a[p][q] === 0) continue;
      const theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
      const t = Math.sign(theta || 1) / (Math.abs(theta) + Math.sqrt(theta * theta + 1));
      const c = 1 / Math.sqrt(t * t + 1);
      const s = t * c;
      for (let k = 0; k < 3; ++k) { // A <- A J
        const akp = a[k][p], akq = a[k][q];
        a[k][p] = c * akp - s * akq;
        a[k][q] = s * akp + c * akq;
      }
      for (let k = 0; k < 3; ++k) { // A <- J^T A
        const apk = a[p][k], aqk = a[q][k];
        a[p][k] = c * apk - s * aqk;
        a[q][k] = s * apk + c * aqk;
      }
      for (let k = 0; k < 3; ++k) { // V <- V J
        const vkp = V[k][p], vkq = V[k][q];
        V[k][p] = c * vkp - s * vkq;
        V[k][q] = s * vkp + c * vkq;
      }
    }
  }
  const det = V[0][0] * (V[1][1] * V[2][2] - V[1][2] * V[2][1]) -
              V[0][1] * (V[1][0] * V[2][2] - V[1][2] * V[2][0]) +
              V[0][2] * (V[1][0] * V[2][1] - V[1][1] * V[2][0]);
  if (det < 0) for (let k = 0; k < 3; ++k) V[k][2] = -V[k][2];
  return { values: [a[0][0], a[1][1], a[2][2]], vectors: V };
}

// ---------------------------------------------------------------------------------------
// scene parsing / validation

function isObj(x) { return x !== null && typeof x === 'object' && !Array.isArray(x); }

function num(x, where, opts = {}) {
  if (x === undefined && 'def' in opts) return opts.def;
  if (typeof x !== 'number' || !Number.isFinite(x)) {
    throw new InputError(`${where}: expected a finite number, got ${JSON.stringify(x)}`);
  }
  if ('min' in opts && x < opts.min) throw new InputError(`${where}: must be >= ${opts.min}, got ${x}`);
  if ('gt' in opts && !(x > opts.gt)) throw new InputError(`${where}: must be > ${opts.gt}, got ${x}`);
  if ('max' in opts && x > opts.max) throw new InputError(`${where}: must be <= ${opts.max}, got ${x}`);
  return x;
}
function optNum(obj, key, where, def, opts = {}) {
  if (obj[key] === undefined || obj[key] === null) return def;
  return num(obj[key], `${where}.${key}`, opts);
}
function int(x, where, opts = {}) {
  const v = num(x, where, opts);
  if (!Number.isInteger(v)) throw new InputError(`${where}: expected an integer, got ${x}`);
  return v;
}
function vec(x, n, where) {
  if (!Array.isArray(x) || x.length !== n) throw new InputError(`${where}: expected an array of ${n} numbers`);
  return x.map((v, i) => num(v, `${where}[${i}]`));
}
function unitQuat(x, where) {
  const q = vec(x, 4, where);
  const n = Math.hypot(q[0], q[1], q[2], q[3]);
  if (!(Math.abs(n - 1) < 1e-6)) throw new InputError(`${where}: quaternion [w,x,y,z] must have unit norm (norm ${n})`);
  return qnormalize(q);
}
function unitVec(x, where) {
  const v = vec(x, 3, where);
  const n = Math.hypot(v[0], v[1], v[2]);
  if (!(Math.abs(n - 1) < 1e-6)) throw new InputError(`${where}: axis must be a unit vector (norm ${n})`);
  return [v[0] / n, v[1] / n, v[2] / n];
}
function bool(x, where, def) {
  if (x === undefined) return def;
  if (typeof x !== 'boolean') throw new InputError(`${where}: expected true or false`);
  return x;
}

// One dof's armature, limits and drive (a revolute or prismatic joint, or a spherical axis).
function parseAxis(A, w) {
  const axis = {};
  axis.armature = optNum(A, 'armature', w, 0, { min: 0 });
  axis.applied_force = optNum(A, 'applied_force', w, 0);
  if (A.limits === undefined || A.limits === null) {
    axis.limits = null;
  } else {
    if (!isObj(A.limits)) throw new InputError(`${w}.limits: expected null or {"lower": .., "upper": ..}`);
    axis.limits = { lower: num(A.limits.lower, `${w}.limits.lower`), upper: num(A.limits.upper, `${w}.limits.upper`) };
    if (!(axis.limits.lower <= axis.limits.upper)) throw new InputError(`${w}.limits: lower must be <= upper`);
  }
  if (A.drive === undefined || A.drive === null) {
    axis.drive = null;
  } else {
    const D = A.drive;
    const wd = `${w}.drive`;
    if (!isObj(D)) throw new InputError(`${wd}: expected null or an object`);
    if (D.type !== 'force' && D.type !== 'acceleration') {
      throw new InputError(`${wd}.type: expected "force" or "acceleration", got ${JSON.stringify(D.type)}`);
    }
    axis.drive = {
      type: D.type,
      stiffness: num(D.stiffness, `${wd}.stiffness`, { min: 0 }),
      damping: num(D.damping, `${wd}.damping`, { min: 0 }),
      max_force: optNum(D, 'max_force', wd, HUGE, { min: 0 }),
      target_position: optNum(D, 'target_position', wd, 0),
      target_velocity: optNum(D, 'target_velocity', wd, 0),
    };
  }
  return axis;
}

// A surface's friction and restitution, each optional (PhysX's PxMaterial; featherdrive's Material
// defaults).
function parseMaterial(M, w) {
  return {
    static_friction: optNum(M, 'static_friction', w, 0.5, { min: 0 }),
    dynamic_friction: optNum(M, 'dynamic_friction', w, 0.5, { min: 0 }),
    restitution: optNum(M, 'restitution', w, 0, { min: 0, max: 1 }),
  };
}

// One collision shape of a link: sphere {radius}, capsule {radius, half_length} (its segment along
// the shape frame's z), box {half_extents}; its frame (xyz, quat) in the link frame.
function parseShape(S, w) {
  if (!isObj(S)) throw new InputError(`${w}: expected an object`);
  const shape = { name: typeof S.name === 'string' ? S.name : '' };
  if (!['sphere', 'capsule', 'box'].includes(S.type)) {
    throw new InputError(`${w}.type: expected "sphere", "capsule" or "box", got ${JSON.stringify(S.type)}`);
  }
  shape.type = S.type;
  if (S.type === 'box') {
    shape.half_extents = vec(S.half_extents, 3, `${w}.half_extents`);
    shape.half_extents.forEach((x, k) => num(x, `${w}.half_extents[${k}]`, { gt: 0 }));
  } else {
    shape.radius = num(S.radius, `${w}.radius`, { gt: 0 });
    if (S.type === 'capsule') shape.half_length = num(S.half_length, `${w}.half_length`, { gt: 0 });
  }
  shape.pose = {
    p: S.xyz === undefined ? [0, 0, 0] : vec(S.xyz, 3, `${w}.xyz`),
    q: S.quat === undefined ? [1, 0, 0, 0] : unitQuat(S.quat, `${w}.quat`),
  };
  shape.material = parseMaterial(S, w);
  return shape;
}

// The ground (the plane normal . x = height) and the contact options of every shape and of it.
function parseContact(doc, s) {
  s.ground = null;
  if (doc.ground !== undefined && doc.ground !== null) {
    const G = doc.ground;
    if (!isObj(G)) throw new InputError('scene.ground: expected null or an object');
    s.ground = {
      height: optNum(G, 'height', 'scene.ground', 0),
      normal: G.normal === undefined ? [0, 0, 1] : unitVec(G.normal, 'scene.ground.normal'),
      material: parseMaterial(G, 'scene.ground'),
    };
  }
  const C = doc.contact === undefined || doc.contact === null ? {} : doc.contact;
  if (!isObj(C)) throw new InputError('scene.contact: expected an object');
  s.contact = {
    contact_offset: optNum(C, 'contact_offset', 'scene.contact', DEFAULT_CONTACT_OFFSET, { min: 0 }),
    rest_offset: optNum(C, 'rest_offset', 'scene.contact', 0),
    bounce_threshold: optNum(C, 'bounce_threshold', 'scene.contact', DEFAULT_BOUNCE_THRESHOLD, { min: 0 }),
  };
  if (!(s.contact.rest_offset < s.contact.contact_offset)) {
    throw new InputError(`scene.contact.rest_offset: must be below contact_offset (${s.contact.contact_offset}), got ${s.contact.rest_offset}`);
  }
}

function parseScene(doc) {
  if (!isObj(doc)) throw new InputError('scene: top level must be a JSON object');
  if (doc.format !== FORMAT) throw new InputError(`scene.format: expected "${FORMAT}", got ${JSON.stringify(doc.format)}`);
  const s = {};
  s.dt = num(doc.dt, 'scene.dt', { gt: 0 });
  s.steps = int(doc.steps, 'scene.steps', { min: 0 });
  s.gravity = vec(doc.gravity, 3, 'scene.gravity');
  if (!isObj(doc.solver)) throw new InputError('scene.solver: expected an object');
  if (doc.solver.type !== 'pgs' && doc.solver.type !== 'tgs') {
    throw new InputError(`scene.solver.type: expected "pgs" or "tgs", got ${JSON.stringify(doc.solver.type)}`);
  }
  s.solver = {
    type: doc.solver.type,
    position_iterations: int(doc.solver.position_iterations, 'scene.solver.position_iterations', { min: 1, max: 255 }),
    velocity_iterations: int(doc.solver.velocity_iterations, 'scene.solver.velocity_iterations', { min: 0, max: 255 }),
  };
  s.drive_limits_are_forces = bool(doc.drive_limits_are_forces, 'scene.drive_limits_are_forces', true);
  s.floating_base = bool(doc.floating_base, 'scene.floating_base', false);

  const root = doc.root === undefined ? {} : doc.root;
  if (!isObj(root)) throw new InputError('scene.root: expected an object');
  s.root = {
    position: root.position === undefined ? [0, 0, 0] : vec(root.position, 3, 'scene.root.position'),
    quat: root.quat === undefined ? [1, 0, 0, 0] : unitQuat(root.quat, 'scene.root.quat'),
    linear_velocity: root.linear_velocity === undefined ? [0, 0, 0] : vec(root.linear_velocity, 3, 'scene.root.linear_velocity'),
    angular_velocity: root.angular_velocity === undefined ? [0, 0, 0] : vec(root.angular_velocity, 3, 'scene.root.angular_velocity'),
  };

  if (!Array.isArray(doc.links) || doc.links.length === 0) throw new InputError('scene.links: expected a non-empty array');
  if (doc.links.length > 255) throw new InputError(`scene.links: PhysX 5.6.1 allows at most 255 links, got ${doc.links.length}`);
  const linkNames = new Set();
  const jointNames = new Map();
  s.links = doc.links.map((L, i) => {
    const w = `scene.links[${i}]`;
    if (!isObj(L)) throw new InputError(`${w}: expected an object`);
    const link = {};
    link.name = typeof L.name === 'string' && L.name ? L.name : `link${i}`;
    if (linkNames.has(link.name)) throw new InputError(`${w}.name: duplicate link name "${link.name}"`);
    linkNames.add(link.name);
    link.parent = int(L.parent, `${w}.parent`, { min: -1 });
    if (i === 0 && link.parent !== -1) throw new InputError(`${w}.parent: the first link is the root and must have parent -1`);
    if (i > 0 && !(link.parent >= 0 && link.parent < i)) {
      throw new InputError(`${w}.parent: must be the index of an earlier link (0..${i - 1}), got ${link.parent}`);
    }
    link.mass = num(L.mass, `${w}.mass`, { gt: 0 });
    link.com = L.com === undefined ? [0, 0, 0] : vec(L.com, 3, `${w}.com`);
    const I = vec(L.inertia, 6, `${w}.inertia`);
    const [ixx, iyy, izz, ixy, ixz, iyz] = I;
    const eig = symmetricEigen3([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]);
    const tol = 1e-12 * Math.max(Math.abs(ixx), Math.abs(iyy), Math.abs(izz));
    for (const e of eig.values) {
      if (!(e > tol)) throw new InputError(`${w}.inertia: tensor must be positive definite (principal moments ${eig.values.join(', ')})`);
    }
    link.principal_moments = eig.values;
    link.principal_quat = quatFromMatrix(eig.vectors);
    link.linear_damping = optNum(L, 'linear_damping', w, 0, { min: 0 });
    link.angular_damping = optNum(L, 'angular_damping', w, 0, { min: 0 });
    link.max_linear_velocity = Math.min(optNum(L, 'max_linear_velocity', w, HUGE, { min: 0 }), PHYSX_MAX_LINK_VELOCITY);
    link.max_angular_velocity = Math.min(optNum(L, 'max_angular_velocity', w, HUGE, { min: 0 }), PHYSX_MAX_LINK_VELOCITY);
    link.cfm_scale = optNum(L, 'cfm_scale', w, 0, { min: 0, max: 1 });
    if (L.shapes !== undefined && L.shapes !== null && !Array.isArray(L.shapes)) {
      throw new InputError(`${w}.shapes: expected an array`);
    }
    link.shapes = (L.shapes || []).map((S, k) => parseShape(S, `${w}.shapes[${k}]`));

    const J = L.joint;
    if (i === 0) {
      if (J !== undefined && J !== null) throw new InputError(`${w}.joint: the root link has no inbound joint (must be null)`);
      link.joint = null;
      return link;
    }
    const wj = `${w}.joint`;
    if (!isObj(J)) throw new InputError(`${wj}: every non-root link needs a joint object`);
    const joint = {};
    joint.name = typeof J.name === 'string' && J.name ? J.name : `joint${i}`;
    if (jointNames.has(joint.name)) throw new InputError(`${wj}.name: duplicate joint name "${joint.name}"`);
    // Any name the CSV header can quote (RFC 4180); a line break would split the header's line.
    if (/[\r\n]/.test(joint.name)) throw new InputError(`${wj}.name: joint names must not contain line breaks (${JSON.stringify(joint.name)})`);
    jointNames.set(joint.name, i);
    if (!['revolute', 'prismatic', 'fixed', 'spherical'].includes(J.type)) {
      throw new InputError(`${wj}.type: expected "revolute", "prismatic", "spherical" or "fixed", got ${JSON.stringify(J.type)}`);
    }
    joint.type = J.type;
    if (!isObj(J.origin)) throw new InputError(`${wj}.origin: expected {"xyz": [...], "quat": [w,x,y,z]}`);
    joint.origin = {
      p: J.origin.xyz === undefined ? [0, 0, 0] : vec(J.origin.xyz, 3, `${wj}.origin.xyz`),
      q: J.origin.quat === undefined ? [1, 0, 0, 0] : unitQuat(J.origin.quat, `${wj}.origin.quat`),
    };
    if (joint.type === 'spherical') {
      // Its axes are the joint frame's; per axis: armature, limits, drive (parseAxis).
      joint.axis = [1, 0, 0];
      if (!Array.isArray(J.axes) || J.axes.length !== 3) {
        throw new InputError(`${wj}.axes: expected 3 objects (twist, swing1, swing2)`);
      }
      joint.axes = J.axes.map((A, k) => {
        const wa = `${wj}.axes[${k}]`;
        if (!isObj(A)) throw new InputError(`${wa}: expected an object`);
        const axis = parseAxis(A, wa);
        for (const side of ['lower', 'upper']) {
          if (axis.limits && !(Math.abs(axis.limits[side]) <= Math.PI)) {
            throw new InputError(`${wa}.limits.${side}: a spherical axis's limit must lie in [-pi, pi], got ${axis.limits[side]}`);
          }
        }
        return { name: `${joint.name}:${SPHERICAL_AXES[k]}`, type: 'spherical', index: k, ...axis };
      });
      for (const a of joint.axes) jointNames.set(a.name, i);
    } else if (joint.type === 'fixed') {
      if (J.drive !== undefined && J.drive !== null) throw new InputError(`${wj}.drive: a fixed joint cannot have a drive`);
      if (J.limits !== undefined && J.limits !== null) throw new InputError(`${wj}.limits: a fixed joint cannot have limits`);
    } else {
      joint.axis = unitVec(J.axis, `${wj}.axis`);
    }
    // PhysX's eREVOLUTE wraps the position past +-2 pi; eREVOLUTE_UNWRAPPED (the default) does not.
    joint.wrapped = bool(J.wrapped, `${wj}.wrapped`, false);
    if (joint.wrapped && joint.type !== 'revolute') {
      throw new InputError(`${wj}.wrapped: only a revolute joint wraps`);
    }
    joint.friction_coefficient = optNum(J, 'friction_coefficient', wj, 0, { min: 0 });
    joint.max_velocity = optNum(J, 'max_velocity', wj, HUGE, { min: 0 });
    if (joint.type !== 'spherical') Object.assign(joint, parseAxis(J, wj));
    link.joint = joint;
    return link;
  });

  const movable = (name, where) => {
    if (!jointNames.has(name)) throw new InputError(`${where}: unknown joint "${name}"`);
    const li = jointNames.get(name);
    if (s.links[li].joint.type === 'fixed') throw new InputError(`${where}: joint "${name}" is fixed and has no coordinate`);
    if (s.links[li].joint.type === 'spherical' && s.links[li].joint.name === name) {
      throw new InputError(`${where}: joint "${name}" is spherical: name its axes (${SPHERICAL_AXES.map((a) => `"${name}:${a}"`).join(', ')})`);
    }
    return li;
  };
  s.initial = { q: new Map(), qd: new Map() };
  if (doc.initial !== undefined && doc.initial !== null) {
    if (!isObj(doc.initial)) throw new InputError('scene.initial: expected an object');
    for (const key of ['q', 'qd']) {
      const m = doc.initial[key];
      if (m === undefined || m === null) continue;
      if (!isObj(m)) throw new InputError(`scene.initial.${key}: expected an object {joint: value}`);
      for (const [name, v] of Object.entries(m)) {
        movable(name, `scene.initial.${key}`);
        s.initial[key].set(name, num(v, `scene.initial.${key}.${name}`));
      }
    }
  }
  s.targets = [];
  if (doc.targets !== undefined && doc.targets !== null) {
    if (!Array.isArray(doc.targets)) throw new InputError('scene.targets: expected an array');
    doc.targets.forEach((entry, k) => {
      const w = `scene.targets[${k}]`;
      if (!isObj(entry)) throw new InputError(`${w}: expected an object {joint: [position, velocity]}`);
      const m = new Map();
      for (const [name, pv] of Object.entries(entry)) {
        movable(name, w);
        const v = vec(pv, 2, `${w}.${name}`);
        m.set(name, v);
      }
      s.targets.push(m);
    });
  }
  // forces[k]: joint forces {joint: value} applied through step k + 1 (PhysX's cache jointForce);
  // a joint it leaves out keeps its applied_force.
  s.forces = [];
  if (doc.forces !== undefined && doc.forces !== null) {
    if (!Array.isArray(doc.forces)) throw new InputError('scene.forces: expected an array');
    doc.forces.forEach((entry, k) => {
      const w = `scene.forces[${k}]`;
      if (!isObj(entry)) throw new InputError(`${w}: expected an object {joint: force}`);
      const m = new Map();
      for (const [name, f] of Object.entries(entry)) {
        movable(name, w);
        m.set(name, num(f, `${w}.${name}`));
      }
      s.forces.push(m);
    });
  }
  parseContact(doc, s);
  return s;
}

// ---------------------------------------------------------------------------------------
// PhysX scene construction

function physxErrorName(P, code) {
  for (const k of ['eNO_ERROR', 'eDEBUG_INFO', 'eDEBUG_WARNING', 'eINVALID_PARAMETER', 'eINVALID_OPERATION',
    'eOUT_OF_MEMORY', 'eINTERNAL_ERROR', 'eABORT', 'ePERF_WARNING']) {
    if (P.PxErrorCodeEnum[k] === code) return k;
  }
  return `code ${code}`;
}

// Reads a C string from wasm memory (UTF8ToString is not exported by this build).
function readCString(P, ptr, maxLen = 4096) {
  if (!ptr) return '';
  const h = P.NativeArrayHelpers.prototype;
  const bytes = [];
  for (let i = 0; i < maxLen; ++i) {
    const b = h.getU8At(ptr + i, 0);
    if (b === 0) break;
    bytes.push(b);
  }
  return Buffer.from(bytes).toString('utf8');
}

let sharedWorld = null;

// Creates (once per process) foundation, physics and a dispatcher with no worker threads.
function getWorld(P) {
  if (sharedWorld) return sharedWorld;
  const messages = [];
  const errorCallback = new P.PxErrorCallbackImpl();
  errorCallback.reportError = (code, message, file, line) => {
    const name = physxErrorName(P, code);
    const text = `PhysX ${name}: ${readCString(P, message)} (${readCString(P, file)}:${line})`;
    const severe = !(code === P.PxErrorCodeEnum.eDEBUG_INFO || code === P.PxErrorCodeEnum.eDEBUG_WARNING ||
                     code === P.PxErrorCodeEnum.ePERF_WARNING);
    messages.push({ severe, text });
  };
  const allocator = new P.PxDefaultAllocator();
  const version = P.PHYSICS_VERSION;
  const foundation = P.CreateFoundation(version, allocator, errorCallback);
  const tolerances = new P.PxTolerancesScale();
  const physics = P.CreatePhysics(version, foundation, tolerances);
  const dispatcher = P.DefaultCpuDispatcherCreate(0);
  sharedWorld = { P, messages, errorCallback, allocator, foundation, physics, dispatcher, tolerances };
  return sharedWorld;
}

function pxVec3(P, v) { return new P.PxVec3(v[0], v[1], v[2]); }
function pxQuat(P, q) { return new P.PxQuat(q[1], q[2], q[3], q[0]); } // PxQuat(x, y, z, w)
function pxTransform(P, pose) { return new P.PxTransform(pxVec3(P, pose.p), pxQuat(P, pose.q)); }
function fromPxVec3(v) { return [v.x, v.y, v.z]; }

// Contact reports for a scene with a ground. PhysX's default filter shader solves contacts but
// reports none; the bindings' pass-through shader gives every pair the default solve flags plus
// the notifications, and the callback below collects each step's points (PxContactPairPoint:
// position, normal, separation and impulse = normal impulse x normal; no friction impulses).
function contactReports(P, sceneDesc) {
  const F = P.PxPairFlagEnum;
  const pairFlags = F.eSOLVE_CONTACT | F.eDETECT_DISCRETE_CONTACT | F.eNOTIFY_TOUCH_FOUND |
                    F.eNOTIFY_TOUCH_PERSISTS | F.eNOTIFY_CONTACT_POINTS;
  const shader = new P.PassThroughFilterShaderImpl();
  shader.filterShader = function filterShader() { this.outputPairFlags = pairFlags; return 0; };
  P.setupPassThroughFilterShader(sceneDesc, shader);
  const capacity = 64;  // a box on a plane has at most 8 points
  const r = { shader, shapeLink: new Map(), pairs: [], buffer: new P.PxArray_PxContactPairPoint(capacity) };
  const callback = new P.PxSimulationEventCallbackImpl();
  callback.onContact = (headerPtr, pairsPtr, nbPairs) => {
    const first = P.wrapPointer(pairsPtr, P.PxContactPair);
    for (let i = 0; i < nbPairs; ++i) {
      const pair = P.NativeArrayHelpers.prototype.getContactPairAt(first, i);
      const n = pair.extractContacts(r.buffer.begin(), capacity);
      const impulse = [0, 0, 0];
      for (let c = 0; c < n; ++c) {
        const pt = r.buffer.get(c);
        impulse[0] += pt.impulse.x; impulse[1] += pt.impulse.y; impulse[2] += pt.impulse.z;
      }
      r.pairs.push({ shapes: [P.getPointer(pair.get_shapes(0)), P.getPointer(pair.get_shapes(1))], impulse });
    }
  };
  callback.onConstraintBreak = () => {};
  callback.onWake = () => {};
  callback.onSleep = () => {};
  callback.onTrigger = () => {};
  sceneDesc.simulationEventCallback = callback;
  r.callback = callback;
  return r;
}

// Builds the scene and the articulation; returns a handle used by step()/readState().
function build(P, s) {
  const world = getWorld(P);
  const { physics } = world;
  world.messages.length = 0;

  const sceneDesc = new P.PxSceneDesc(world.tolerances);
  sceneDesc.gravity = pxVec3(P, s.gravity);
  sceneDesc.cpuDispatcher = world.dispatcher;
  sceneDesc.solverType = s.solver.type === 'tgs' ? P.PxSolverTypeEnum.eTGS : P.PxSolverTypeEnum.ePGS;
  sceneDesc.bounceThresholdVelocity = s.contact.bounce_threshold;
  const contacts = s.ground ? contactReports(P, sceneDesc) : null;
  if (!contacts) sceneDesc.filterShader = P.DefaultFilterShader();
  const scene = physics.createScene(sceneDesc);
  if (!scene) throw new Error('PhysX could not create the scene');
  // Materials by value, one PxMaterial each (PhysX averages a pair's values: C1's section 1).
  const materials = new Map();
  const material = (M) => {
    const key = `${M.static_friction},${M.dynamic_friction},${M.restitution}`;
    if (!materials.has(key)) {
      materials.set(key, physics.createMaterial(M.static_friction, M.dynamic_friction, M.restitution));
    }
    return materials.get(key);
  };
  const offsets = (shape) => {
    shape.setContactOffset(s.contact.contact_offset);
    shape.setRestOffset(s.contact.rest_offset);
  };
  // The ground first, as PxCreatePlane makes it: a static actor whose one shape is the plane
  // through the frame's origin with normal x (PxPlane n . x + d = 0, d = -height).
  let plane = null;
  if (s.ground) {
    const n = s.ground.normal;
    plane = P.CreatePlane(physics, new P.PxPlane(n[0], n[1], n[2], -s.ground.height),
                          material(s.ground.material), new P.PxFilterData(0, 0, 0, 0));
    if (!plane) throw new InputError('PhysX could not create the ground plane');
    const buf = new P.PxArray_PxShapePtr(1);
    plane.getShapes(buf.begin(), 1, 0);
    offsets(buf.get(0));
    scene.addActor(plane);
  }

  const art = physics.createArticulationReducedCoordinate();
  art.setArticulationFlag(P.PxArticulationFlagEnum.eFIX_BASE, !s.floating_base);
  art.setArticulationFlag(P.PxArticulationFlagEnum.eDRIVE_LIMITS_ARE_FORCES, s.drive_limits_are_forces);
  art.setArticulationFlag(P.PxArticulationFlagEnum.eDISABLE_SELF_COLLISION, true);
  art.setSolverIterationCounts(s.solver.position_iterations, s.solver.velocity_iterations);
  art.setSleepThreshold(0);
  art.setStabilizationThreshold(0);

  // World poses of the link frames at q = 0 (only used to create the links; the joint
  // positions set below are authoritative).
  const rootPose = { p: s.root.position, q: s.root.quat };
  const poses = [];
  const links = [];
  const joints = [];
  s.links.forEach((L, i) => {
    const pose = i === 0 ? rootPose : compose(poses[L.parent], L.joint.origin);
    poses.push(pose);
    const link = art.createLink(i === 0 ? null : links[L.parent], pxTransform(P, pose));
    if (!link) throw new InputError(`PhysX could not create link "${L.name}"`);
    link.setMass(L.mass);
    link.setCMassLocalPose(pxTransform(P, { p: L.com, q: L.principal_quat }));
    link.setMassSpaceInertiaTensor(pxVec3(P, L.principal_moments));
    link.setLinearDamping(L.linear_damping);
    link.setAngularDamping(L.angular_damping);
    link.setMaxLinearVelocity(L.max_linear_velocity);
    link.setMaxAngularVelocity(L.max_angular_velocity);
    link.setCfmScale(L.cfm_scale);
    for (const S of L.shapes) {
      const geometry = S.type === 'sphere' ? new P.PxSphereGeometry(S.radius)
        : S.type === 'capsule' ? new P.PxCapsuleGeometry(S.radius, S.half_length)
          : new P.PxBoxGeometry(S.half_extents[0], S.half_extents[1], S.half_extents[2]);
      const shape = physics.createShape(geometry, material(S.material), true);
      if (!shape) throw new InputError(`PhysX could not create shape ${JSON.stringify(S.name)} of link "${L.name}"`);
      offsets(shape);
      // The local pose is relative to the link's actor frame, which is the scene's link frame
      // (the centre of mass is cMassLocalPose, set above).
      const q = S.type === 'capsule' ? qnormalize(qmul(S.pose.q, Q_CAPSULE_X_TO_Z)) : S.pose.q;
      shape.setLocalPose(pxTransform(P, { p: S.pose.p, q }));
      link.attachShape(shape);
      if (contacts) contacts.shapeLink.set(P.getPointer(shape), i);
    }
    links.push(link);

    if (i === 0) { joints.push(null); return; }
    const J = L.joint;
    const pj = link.getInboundJoint();
    // A spherical joint's axes are its joint frame's, and a fixed joint (an MJCF body welded to
    // its parent) has none: the child joint frame is the link frame.
    const R = J.type === 'spherical' || J.type === 'fixed' ? [1, 0, 0, 0] : rotationXTo(J.axis);
    pj.setParentPose(pxTransform(P, { p: J.origin.p, q: qnormalize(qmul(J.origin.q, R)) }));
    pj.setChildPose(pxTransform(P, { p: [0, 0, 0], q: R }));
    let axis = null;
    const setAxis = (ax, spec) => {
      if (spec.limits) {
        pj.setMotion(ax, P.PxArticulationMotionEnum.eLIMITED);
        pj.setLimitParams(ax, new P.PxArticulationLimit(spec.limits.lower, spec.limits.upper));
      } else {
        pj.setMotion(ax, P.PxArticulationMotionEnum.eFREE);
      }
      pj.setArmature(ax, spec.armature);
      if (spec.drive) {
        const type = spec.drive.type === 'acceleration' ? P.PxArticulationDriveTypeEnum.eACCELERATION
                                                        : P.PxArticulationDriveTypeEnum.eFORCE;
        pj.setDriveParams(ax, new P.PxArticulationDrive(spec.drive.stiffness, spec.drive.damping, spec.drive.max_force, type));
        pj.setDriveTarget(ax, spec.drive.target_position);
        pj.setDriveVelocity(ax, spec.drive.target_velocity);
      }
    };
    if (J.type === 'spherical') {
      pj.setJointType(P.PxArticulationJointTypeEnum.eSPHERICAL);
      const A = P.PxArticulationAxisEnum;
      const enums = [A.eTWIST, A.eSWING1, A.eSWING2];
      J.axes.forEach((spec, k) => setAxis(enums[k], spec));
      pj.setFrictionCoefficient(J.friction_coefficient);
      pj.setMaxJointVelocity(J.max_velocity);
      joints.push({ px: pj, axis: null, spec: J, linkIndex: i, childRot: R,
                    axes: J.axes.map((spec, k) => ({ px: pj, axis: enums[k], spec, linkIndex: i, childRot: R })) });
      return;
    }
    if (J.type === 'fixed') {
      pj.setJointType(P.PxArticulationJointTypeEnum.eFIX);
    } else {
      if (J.type === 'revolute') {
        pj.setJointType(J.wrapped ? P.PxArticulationJointTypeEnum.eREVOLUTE
                                  : JOINT_TYPE_REVOLUTE_UNWRAPPED);
        axis = P.PxArticulationAxisEnum.eTWIST;
      } else {
        pj.setJointType(P.PxArticulationJointTypeEnum.ePRISMATIC);
        axis = P.PxArticulationAxisEnum.eX;
      }
      setAxis(axis, J);
    }
    pj.setFrictionCoefficient(J.friction_coefficient);
    pj.setMaxJointVelocity(J.max_velocity);
    joints.push({ px: pj, axis, spec: J, linkIndex: i, childRot: R });
  });

  if (!scene.addArticulation(art)) throw new Error('PhysX refused to add the articulation to the scene');
  art.setWakeCounter(1e9);

  // Initial state: one entry per coordinate (a spherical joint's three axes apart).
  const movableJoints = [];
  for (const j of joints) {
    if (j && j.axes) movableJoints.push(...j.axes);
    else if (j && j.axis !== null) movableJoints.push(j);
  }
  for (const j of movableJoints) {
    j.px.setJointPosition(j.axis, s.initial.q.get(j.spec.name) || 0);
    j.px.setJointVelocity(j.axis, s.initial.qd.get(j.spec.name) || 0);
  }
  art.setRootGlobalPose(pxTransform(P, rootPose));
  if (s.floating_base) {
    // PhysX's root linear velocity is that of the root's centre of mass.
    const w = s.root.angular_velocity;
    const vCom = add(s.root.linear_velocity, cross(w, qrot(s.root.quat, s.links[0].com)));
    art.setRootLinearVelocity(pxVec3(P, vCom));
    art.setRootAngularVelocity(pxVec3(P, w));
  }
  const KF = P.PxArticulationKinematicFlagEnum;
  art.updateKinematic(new P.PxArticulationKinematicFlags(KF.ePOSITION | KF.eVELOCITY));
  art.wakeUp();
  art.setWakeCounter(1e9);

  // Internal dof index of every movable joint (dofs are numbered by PhysX link index).
  const byIndex = joints.filter((j) => j).map((j) => ({ j, idx: links[j.linkIndex].getLinkIndex() }))
    .sort((a, b) => a.idx - b.idx);
  let dof = 0;
  for (const { j } of byIndex) {
    const n = links[j.linkIndex].getInboundJointDof();
    j.dofIndex = j.axis === null ? -1 : dof;
    if (j.axes) j.axes.forEach((a, k) => { a.dofIndex = dof + k; a.physxLinkIndex = links[j.linkIndex].getLinkIndex(); });
    j.physxLinkIndex = links[j.linkIndex].getLinkIndex();
    dof += n;
  }
  if (dof !== art.getDofs()) throw new Error(`internal: dof count mismatch (${dof} vs ${art.getDofs()})`);

  const cache = art.createCache();
  const CF = P.PxArticulationCacheFlagEnum;
  const cacheFlags = new P.PxArticulationCacheFlags(CF.eLINK_INCOMING_JOINT_FORCE | CF.eACCELERATION);
  const anyForce = s.forces.length > 0 || movableJoints.some((j) => j.spec.applied_force !== 0);
  const h = {
    P, world, s, scene, art, links, joints, movableJoints, cache, cacheFlags, anyForce, stepCount: 0,
    contacts, plane, materials: [...materials.values()],
    contactLinks: contacts ? s.links.map((L, i) => i).filter((i) => s.links[i].shapes.length) : [],
  };
  return h;
}

function severeMessages(h) {
  return h.world.messages.filter((m) => m.severe).map((m) => m.text);
}

// Sets drive targets for the joints named in map {name: [pos, vel]}.
function setTargets(h, map) {
  for (const j of h.movableJoints) {
    const t = map.get(j.spec.name);
    if (!t) continue;
    j.px.setDriveTarget(j.axis, t[0]);
    j.px.setDriveVelocity(j.axis, t[1]);
  }
}

// Joint forces of step k (1-based) through the articulation cache's jointForce, every dof written
// (forces[k - 1] where it names the joint, else the joint's applied_force).
function setForces(h, k) {
  const { P, art, cache } = h;
  if (!h.anyForce) return;
  const helpers = P.NativeArrayHelpers.prototype;
  if (!h.jointForceArray) {
    // cache.jointForce comes back as the address of the member (see readForces) and setRealAt
    // writes at the address it is given: the array's address is the pointer stored in the
    // member, read through a scratch word that holds the member's address (getU32At dereferences).
    const scratch = P.getPointer(new P.PxVec3(0, 0, 0));
    helpers.setU32At(scratch, 0, P.getPointer(cache.jointForce));
    h.jointForceArray = helpers.getU32At(scratch, 0);
  }
  const m = k - 1 < h.s.forces.length ? h.s.forces[k - 1] : null;
  for (let d = 0; d < art.getDofs(); ++d) helpers.setRealAt(h.jointForceArray, d, 0);
  for (const j of h.movableJoints) {
    const f = m && m.has(j.spec.name) ? m.get(j.spec.name) : j.spec.applied_force;
    helpers.setRealAt(h.jointForceArray, j.dofIndex, f);
  }
  art.applyCache(cache, new P.PxArticulationCacheFlags(P.PxArticulationCacheFlagEnum.eFORCE));
}
function linkPose(link) {
  const t = link.getGlobalPose();
  return { p: [t.p.x, t.p.y, t.p.z], q: [t.q.w, t.q.x, t.q.y, t.q.z] };
}

function step(h) {
  // Link poses at the start of the step, needed to read the drive forces (readForces).
  h.prePoses = h.movableJoints.map((j) => linkPose(h.links[j.linkIndex]));
  if (h.contacts) h.contacts.pairs.length = 0;
  h.scene.simulate(h.s.dt);
  h.scene.fetchResults(true);
  h.stepCount += 1;
}

// Drive force of every movable joint over the last step (see README.md, "Drive forces").
//
// PhysX 5.6.1 reports no per-dof solver force. What it offers is the incoming joint force
// (PxArticulationCacheFlag::eLINK_INCOMING_JOINT_FORCE), the spatial force the parent
// transmits to the child over the step, computed on the CPU as
//     I_art (a_free + dv_solver / dt) + Z_art
// from the start-of-step articulated inertia and bias forces, but moved to the joint point
// and rotated into the child joint frame using the link's END-of-step pose. Its component
// along the joint axis is the joint-space force, once the lever arm and the axis are taken
// at the start-of-step pose again (done here from the full 6-vector and the link poses
// before and after the step), and once the armature's share (armature * qdd, which does
// not pass through the link) is added back.
function readForces(h) {
  const { P, art, cache, cacheFlags } = h;
  if (h.stepCount === 0 || !h.prePoses) return h.movableJoints.map(() => 0);
  art.copyInternalStateToCache(cache, cacheFlags);
  // Quirk of this binding: a PxRealPtr member (jointAcceleration) comes back as the
  // address of the member, which NativeArrayHelpers.getRealAt dereferences; a
  // PxSpatialForce* member (linkIncomingJointForce) comes back as the array itself.
  const getReal = P.NativeArrayHelpers.prototype.getRealAt;
  const forces = cache.linkIncomingJointForce.ptr; // PxSpatialForce[nbLinks], 32 bytes each
  return h.movableJoints.map((j, n) => {
    if (!j.spec.drive) return 0; // no drive, no drive force (the joint may still carry limit forces)
    const sf = P.wrapPointer(forces + 32 * j.physxLinkIndex, P.PxSpatialForce);
    const Frep = [sf.force.x, sf.force.y, sf.force.z];
    const Trep = [sf.torque.x, sf.torque.y, sf.torque.z];
    const com = h.s.links[j.linkIndex].com;
    const R = j.childRot; // child joint frame in the link frame (origin at the link origin)
    const pre = h.prePoses[n];
    const post = linkPose(h.links[j.linkIndex]);
    const Qnew = qmul(post.q, R);
    const Qold = qmul(pre.q, R);
    const F = qrot(Qnew, Frep); // world
    const axisOld = qrot(Qold, j.spec.type === 'spherical' ? [0, 0, 0].map((_, k) => (k === j.spec.index ? 1 : 0)) : [1, 0, 0]);
    let transmitted;
    if (j.spec.type === 'revolute' || j.spec.type === 'spherical') {
      // torque about the COM, then about the joint point of the start-of-step pose;
      // the joint point is the link origin, so COM -> joint = -Q com
      const dNew = qrot(post.q, com).map((x) => -x);
      const dOld = qrot(pre.q, com).map((x) => -x);
      const tauCom = add(qrot(Qnew, Trep), cross(dNew, F));
      const tauOld = sub(tauCom, cross(dOld, F));
      transmitted = dot(axisOld, tauOld);
    } else {
      transmitted = dot(axisOld, F);
    }
    const qdd = getReal(cache.jointAcceleration, j.dofIndex);
    return transmitted + j.spec.armature * qdd;
  });
}

// The ground's force on each link with shapes over the last step: the normal impulses PhysX
// reports for the link's contact points, summed, over dt (world frame, N). A pair's impulse acts
// on its first shape (PxContactPairPoint::normal points the way shape 0 is pushed).
function readContactForces(h) {
  const force = new Map(h.contactLinks.map((i) => [i, [0, 0, 0]]));
  if (!h.contacts) return [];
  for (const pair of h.contacts.pairs) {
    for (const [k, sign] of [[0, 1], [1, -1]]) {
      const link = h.contacts.shapeLink.get(pair.shapes[k]);
      if (link === undefined) continue;
      const f = force.get(link);
      for (let c = 0; c < 3; ++c) f[c] += sign * pair.impulse[c];
    }
  }
  const out = [];
  for (const i of h.contactLinks) out.push(...force.get(i).map((x) => x / h.s.dt));
  return out;
}

function readState(h) {
  const q = h.movableJoints.map((j) => j.px.getJointPosition(j.axis));
  const qd = h.movableJoints.map((j) => j.px.getJointVelocity(j.axis));
  let root = null;
  if (h.s.floating_base) {
    const link = h.links[0];
    const pose = link.getGlobalPose();
    const p = fromPxVec3(pose.p);
    const qq = [pose.q.w, pose.q.x, pose.q.y, pose.q.z];
    const w = fromPxVec3(link.getAngularVelocity());
    const vCom = fromPxVec3(link.getLinearVelocity());
    const v = sub(vCom, cross(w, qrot(qq, h.s.links[0].com)));
    root = [...p, ...qq, ...w, ...v];
  }
  return { q, qd, root };
}

function csvHeader(h) {
  const names = h.movableJoints.map((j) => j.spec.name);
  const cols = ['step', 't', ...names.map((n) => `q:${n}`), ...names.map((n) => `qd:${n}`), ...names.map((n) => `f:${n}`)];
  if (h.s.floating_base) {
    for (const c of ['px', 'py', 'pz', 'qw', 'qx', 'qy', 'qz', 'wx', 'wy', 'wz', 'vx', 'vy', 'vz']) cols.push(`root:${c}`);
  }
  for (const i of h.contactLinks) {
    for (const c of ['fx', 'fy', 'fz']) cols.push(`contact:${h.s.links[i].name}:${c}`);
  }
  // RFC 4180, as featherdrive writes and reads them: a name with a comma, quote or line break.
  const field = (c) => (/[",\r\n]/.test(c) ? `"${c.replace(/"/g, '""')}"` : c);
  return cols.map(field).join(',');
}

function fmt(x) {
  if (Number.isNaN(x)) return 'nan';
  if (x === Infinity) return 'inf';
  if (x === -Infinity) return '-inf';
  return String(x); // shortest representation that round-trips the double exactly
}

// Runs a parsed scene; returns {header, rows: [[numbers]], asleep}.
function simulate(P, s, onRow) {
  const h = build(P, s);
  const setupErrors = severeMessages(h);
  if (setupErrors.length) throw new InputError('PhysX rejected the scene: ' + setupErrors.join('; '));
  const header = csvHeader(h);
  const rows = [];
  const emit = (k, f) => {
    const st = readState(h);
    const row = [k, k * s.dt, ...st.q, ...st.qd, ...f];
    if (st.root) row.push(...st.root);
    row.push(...(k === 0 ? h.contactLinks.flatMap(() => [0, 0, 0]) : readContactForces(h)));
    rows.push(row);
    if (onRow) onRow(row, h);
  };
  emit(0, h.movableJoints.map(() => 0));
  for (let k = 1; k <= s.steps; ++k) {
    if (k - 1 < s.targets.length) setTargets(h, s.targets[k - 1]);
    setForces(h, k);
    step(h);
    const errs = severeMessages(h);
    if (errs.length) throw new Error(`PhysX error in step ${k}: ` + errs.join('; '));
    emit(k, readForces(h));
  }
  const asleep = h.art.isSleeping();
  return { header, rows, asleep, handle: h };
}

function release(h) {
  try { h.cache.release(); } catch (e) { /* ignore */ }
  try { h.scene.release(); } catch (e) { /* ignore */ }
  try { if (h.plane) h.plane.release(); } catch (e) { /* ignore */ }
  for (const m of h.materials) { try { m.release(); } catch (e) { /* ignore */ } }
}

// One run: SCENE.json in, OUT.csv out. Returns the exit status; messages go to `say` (one line
// each), as they go to stderr from the command line.
function runOnce(P, scenePath, outPath, say) {
  let s;
  try {
    let text;
    try { text = fs.readFileSync(scenePath, 'utf8'); } catch (e) {
      throw new InputError(`cannot read scene file ${scenePath}: ${e.message}`);
    }
    let doc;
    try { doc = JSON.parse(text); } catch (e) {
      throw new InputError(`${scenePath} is not valid JSON: ${e.message}`);
    }
    s = parseScene(doc);
  } catch (e) {
    if (e instanceof InputError) { say(`harness.js: error: ${e.message}`); return 2; }
    throw e;
  }
  let result;
  try {
    result = simulate(P, s);
  } catch (e) {
    if (e instanceof InputError) { say(`harness.js: error: ${e.message}`); return 2; }
    say(`harness.js: error: ${e.message}`);
    return 1;
  }
  const warnings = [...new Set(result.handle.world.messages.filter((m) => !m.severe).map((m) => m.text))];
  for (const w of warnings) say(`harness.js: warning: ${w}`);
  const lines = [result.header, ...result.rows.map((r) => r.map(fmt).join(','))];
  fs.mkdirSync(path.dirname(path.resolve(outPath)), { recursive: true });
  fs.writeFileSync(outPath, lines.join('\n') + '\n');
  if (result.asleep) {
    say('harness.js: error: the articulation is asleep at the end of the run (results are not trustworthy)');
    return 1;
  }
  const bad = result.rows.some((r) => r.some((x) => !Number.isFinite(x)));
  if (bad) {
    say(`harness.js: error: the simulation produced non-finite values (see ${outPath})`);
    return 1;
  }
  release(result.handle);
  return 0;
}

// Serves runs on a Unix socket, PhysX loaded once (the tests' fixture; tests/physx/server.py):
// a request is one line "SCENE.json<TAB>OUT.csv", the answer the exit status on its first line
// and the messages after it. Requests are served one at a time, in arrival order. Exits after
// `idleSeconds` without a request, so that a server nobody stops does not stay.
async function serve(socketPath, idleSeconds) {
  const net = require('net');
  const P = await loadPhysX(__dirname);
  try { fs.unlinkSync(socketPath); } catch (e) { /* not there */ }
  let timer = null;
  const server = net.createServer((conn) => {
    let input = '';
    conn.setEncoding('utf8');
    conn.on('data', (chunk) => {
      input += chunk;
      const end = input.indexOf('\n');
      if (end < 0) return;
      const [scenePath, outPath] = input.slice(0, end).split('\t');
      const said = [];
      let code;
      try {
        code = outPath === undefined ? 2 : runOnce(P, scenePath, outPath, (m) => said.push(m));
        if (outPath === undefined) said.push('harness.js: error: expected SCENE.json<TAB>OUT.csv');
      } catch (e) {
        said.push(`harness.js: error: ${e && e.message ? e.message : e}`);
        code = 1;
      }
      conn.end(`${code}\n${said.join('\n')}${said.length ? '\n' : ''}`);
      rearm();
    });
    conn.on('error', () => { /* the client went away */ });
  });
  const rearm = () => {
    if (timer) clearTimeout(timer);
    timer = setTimeout(() => { server.close(); process.exit(0); }, idleSeconds * 1000);
  };
  rearm();
  server.listen(socketPath);
  return new Promise(() => {});  // runs until idle
}

async function main(argv) {
  const usage = 'usage: node harness.js SCENE.json OUT.csv | node harness.js --serve SOCKET [IDLE_SECONDS]';
  if (argv[0] === '--serve' && (argv.length === 2 || argv.length === 3)) {
    return serve(argv[1], argv.length === 3 ? Number(argv[2]) : 120);
  }
  if (argv.length !== 2) {
    console.error(`harness.js: error: expected 2 arguments\n${usage}`);
    return 2;
  }
  const [scenePath, outPath] = argv;
  const P = await loadPhysX(__dirname);
  return runOnce(P, scenePath, outPath, (m) => console.error(m));
}

module.exports = {
  parseScene, simulate, build, step, setTargets, readState, readForces, readContactForces, csvHeader,
  release,
  InputError, symmetricEigen3, quatFromMatrix, rotationXTo, qrot, qmul,
};

if (require.main === module) {
  main(process.argv.slice(2)).then((code) => { process.exitCode = code; }, (e) => {
    console.error(`harness.js: error: ${e && e.stack ? e.stack : e}`);
    process.exitCode = 1;
  });
}
