// PhysX 5.6.1's own run of a harness scene from bench/physx_chain_scene.cpp, judged as
// bench/divergence_length.cpp judges featherdrive's (docs/benchmarks.md, "Where long chains
// diverge"): diverged when a value stops being finite or the energy (kinetic + the drives' springs
// 1/2 kp (q - target)^2; the scene has no gravity) rises above its initial value by more than
// GAIN n m g (n l) / 2. Prints one JSON line.
//   node bench/physx_chain_divergence.js SCENE.json HARNESS_DIR [GAIN]
// HARNESS_DIR holds harness.js and node_modules/physx-js-webidl (`make physx`: build/physx).
'use strict';
const fs = require('fs');
const path = require('path');

async function main() {
  const [scenePath, harnessDir, gainArg] = process.argv.slice(2);
  const gain = gainArg === undefined ? 1000 : Number(gainArg);
  const harness = require(path.resolve(harnessDir, 'harness.js'));
  const { loadPhysX } = require(path.resolve(harnessDir, 'physx_loader.js'));
  const P = await loadPhysX(path.resolve(harnessDir));
  const doc = JSON.parse(fs.readFileSync(scenePath, 'utf8'));
  const s = harness.parseScene(doc);
  const h = harness.build(P, s);
  const joints = h.movableJoints;
  const n = joints.length;
  const targets = joints.map((j) => j.spec.drive.target_position);
  const kp = joints.map((j) => j.spec.drive.stiffness);
  const bodies = s.links.map((L, i) => ({ link: h.links[i], m: L.mass, I: doc.links[i].inertia }));
  const energy = () => {
    let e = 0;
    for (const b of bodies) {
      const pose = b.link.getGlobalPose();
      const q = [pose.q.w, pose.q.x, pose.q.y, pose.q.z];
      const v = b.link.getLinearVelocity();  // of the centre of mass
      const w = b.link.getAngularVelocity();
      const wl = harness.qrot([q[0], -q[1], -q[2], -q[3]], [w.x, w.y, w.z]);  // link frame
      const [xx, yy, zz, xy, xz, yz] = b.I;
      const Iw = [xx * wl[0] + xy * wl[1] + xz * wl[2], xy * wl[0] + yy * wl[1] + yz * wl[2],
                  xz * wl[0] + yz * wl[1] + zz * wl[2]];
      e += 0.5 * b.m * (v.x * v.x + v.y * v.y + v.z * v.z) +
           0.5 * (wl[0] * Iw[0] + wl[1] * Iw[1] + wl[2] * Iw[2]);
    }
    joints.forEach((j, k) => {
      const d = j.px.getJointPosition(j.axis) - targets[k];
      e += 0.5 * kp[k] * d * d;
    });
    return e;
  };
  const scale = n * 1.0 * 9.81 * n * 0.5 / 2;  // divergence_length.cpp's: weight x length / 2
  const e0 = energy();
  let worst = 0, diverged = false, why = '', step = 0;
  for (step = 1; step <= s.steps; ++step) {
    h.scene.simulate(s.dt);
    h.scene.fetchResults(true);
    const g = (energy() - e0) / scale;
    worst = Math.max(worst, Number.isNaN(g) ? Infinity : g);
    if (!(g <= gain)) { diverged = true; why = `energy gain ${g.toPrecision(3)} at step ${step}`; break; }
  }
  let sq = 0;
  joints.forEach((j, k) => { const d = j.px.getJointPosition(j.axis) - targets[k]; sq += d * d; });
  console.log(JSON.stringify({ links: n, solver: s.solver.type, steps: Math.min(step, s.steps),
                               diverged, why, worst_gain: worst, rms_error: Math.sqrt(sq / n) }));
}
main().catch((e) => { console.error(`physx_chain_divergence.js: ${e.stack || e}`); process.exitCode = 1; });
