// The page of `featherdrive view` (docs/viewer.md): the robot of a run in 3D, posed at every frame
// by the link poses featherdrive computed (no kinematics here), a timeline and per-joint curves.
// Its data is the JSON in <script id="fd-data"> (python/featherdrive_view.py writes it).
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { STLLoader } from 'three/examples/jsm/loaders/STLLoader.js';
import { ColladaLoader } from 'three/examples/jsm/loaders/ColladaLoader.js';
import { ConvexGeometry } from 'three/examples/jsm/geometries/ConvexGeometry.js';
import URDFLoader from 'urdf-loader';

const data = JSON.parse(document.getElementById('fd-data').textContent);
const frames = data.times.length;
const linkCount = data.links.length;
// What tests and users may read (docs/viewer.md, "Page state").
const state = { ready: false, frame: 0, time: 0, meshCount: 0, boxCount: 0, shapeCount: 0,
                shapeTypes: {}, ground: false, playing: false, contactArrows: 0 };
window.featherdrive = state;

// ---- layout -----------------------------------------------------------------------------------
const style = document.createElement('style');
style.textContent = `
body { margin: 0; font: 13px sans-serif; background: #fff; color: #222; }
#fd-view { width: 100%; height: 60vh; display: block; }
#fd-controls { display: flex; gap: 8px; align-items: center; padding: 4px 8px; }
#fd-controls input[type=range] { flex: 1; }
#fd-curves { width: 100%; display: block; }
#fd-legend { padding: 0 8px; color: #555; }`;
document.head.appendChild(style);
const view = document.createElement('canvas');
view.id = 'fd-view';
const controlsBar = document.createElement('div');
controlsBar.id = 'fd-controls';
controlsBar.innerHTML = `<button id="fd-play">play</button>
<input id="fd-time" type="range" min="0" max="${frames - 1}" step="1" value="0">
<span id="fd-clock"></span>
<label>speed <select id="fd-speed"><option>0.25</option><option>0.5</option>
<option selected>1</option><option>2</option><option>4</option></select></label>
<label><input id="fd-frames" type="checkbox"> joint frames and axes</label>
<label id="fd-contacts-label"><input id="fd-contacts" type="checkbox" checked> contact forces
</label>`;
const legend = document.createElement('div');
legend.id = 'fd-legend';
const curves = document.createElement('canvas');
curves.id = 'fd-curves';
document.body.append(view, controlsBar, legend, curves);
const playButton = document.getElementById('fd-play');
const slider = document.getElementById('fd-time');
const clock = document.getElementById('fd-clock');
const speed = document.getElementById('fd-speed');
const framesBox = document.getElementById('fd-frames');
const contactsBox = document.getElementById('fd-contacts');
if (!data.contacts) document.getElementById('fd-contacts-label').style.display = 'none';

// ---- the 3D scene -----------------------------------------------------------------------------
// Some headless and remote browsers have no WebGL: the page then keeps the timeline and the
// curves, and one line says that the 3D view is unavailable. WebGL 2 is probed on a scratch
// canvas first, since three.js logs a console error before it throws.
function makeRenderer() {
  if (!document.createElement('canvas').getContext('webgl2')) return null;
  try {
    return new THREE.WebGLRenderer({ canvas: view, antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    return null;
  }
}
const renderer = makeRenderer();
state.webgl = renderer !== null;
if (renderer) {
  renderer.setPixelRatio(window.devicePixelRatio || 1);
} else {
  view.style.display = 'none';
  const note = document.createElement('div');
  note.id = 'fd-no-webgl';
  note.style.padding = '8px';
  note.textContent = 'The 3D view is unavailable: this browser has no WebGL 2. The timeline and ' +
    'the curves below work without it.';
  document.body.insertBefore(note, view);
}
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xffffff);
scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 2.0));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(3, -2, 5);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(45, 1, 0.001, 1000);
camera.up.set(0, 0, 1);  // featherdrive's world: z up
const orbit = new OrbitControls(camera, view);
orbit.addEventListener('change', () => render());

function decodeBase64(text) {
  const bytes = atob(text);
  const out = new Uint8Array(bytes.length);
  for (let i = 0; i < bytes.length; ++i) out[i] = bytes.charCodeAt(i);
  return out;
}

// Meshes come inlined in the page (base64, keyed by the URDF's filename attribute); one the
// writer could not find was reported there and is left out here.
function loadInlinedMesh(path, manager, material, done) {
  const encoded = data.meshes[path];
  if (encoded === undefined) { done(null); return; }
  const bytes = decodeBase64(encoded);
  if (/\.stl$/i.test(path)) {
    const geometry = new STLLoader(manager).parse(bytes.buffer);
    geometry.computeVertexNormals();
    state.meshCount += 1;
    done(new THREE.Mesh(geometry, material || new THREE.MeshPhongMaterial()));
  } else if (/\.dae$/i.test(path)) {
    const collada = new ColladaLoader(manager).parse(new TextDecoder().decode(bytes), '');
    state.meshCount += 1;
    done(collada.scene);
  } else {
    done(null);
  }
}

// One Object3D per link name, at the world root: each is posed directly from data.poses.
const linkObjects = {};
const hasVisual = {};
if (data.urdf) {
  const loader = new URDFLoader();
  loader.packages = (name) => 'package://' + name;  // keeps the filename as the URDF wrote it
  loader.loadMeshCb = loadInlinedMesh;
  const robot = loader.parse(data.urdf);
  for (const [name, link] of Object.entries(robot.links)) {
    hasVisual[name] = link.children.some((o) => o.isURDFVisual && o.children.length > 0);
  }
  for (const [name, link] of Object.entries(robot.links)) {
    scene.add(link);  // detached from its joint: the pose comes from featherdrive
    linkObjects[name] = link;
  }
}
for (const name of data.links) {
  if (!linkObjects[name]) {
    linkObjects[name] = new THREE.Group();
    scene.add(linkObjects[name]);
  }
}

// A link with no visual (nor any link merged into it) is drawn as its collision shapes, or as its
// equivalent-inertia box where it has none.
const boxMaterial = new THREE.MeshPhongMaterial({ color: 0x8899aa });
const shapeMaterial = new THREE.MeshPhongMaterial({ color: 0xb08a5a });

function basis(a) {  // axes in the link frame, one after the other, as a rotation
  return new THREE.Quaternion().setFromRotationMatrix(new THREE.Matrix4().makeBasis(
    new THREE.Vector3(a[0], a[1], a[2]), new THREE.Vector3(a[3], a[4], a[5]),
    new THREE.Vector3(a[6], a[7], a[8])));
}

// A shape's geometry in its own frame (docs/viewer.md): three.js builds capsules and cylinders
// along y, featherdrive's lie along z.
function shapeGeometry(shape) {
  const s = shape.size;
  switch (shape.type) {
    case 'sphere': return new THREE.SphereGeometry(s[0], 24, 16);
    case 'capsule': return new THREE.CapsuleGeometry(s[0], 2 * s[1], 8, 24).rotateX(Math.PI / 2);
    case 'cylinder':
      return new THREE.CylinderGeometry(s[0], s[0], 2 * s[1], 24).rotateX(Math.PI / 2);
    case 'box': return new THREE.BoxGeometry(2 * s[0], 2 * s[1], 2 * s[2]);
    case 'ellipsoid': return new THREE.SphereGeometry(1, 24, 16).scale(s[0], s[1], s[2]);
    case 'convex': {
      const v = shape.vertices;
      const points = [];
      for (let k = 0; k + 2 < v.length; k += 3) {
        points.push(new THREE.Vector3(v[k], v[k + 1], v[k + 2]));
      }
      return new ConvexGeometry(points);
    }
    default: return null;
  }
}

function hasVisualOrMerged(name) {
  const merged = Object.keys(data.merged_into).filter((m) => data.merged_into[m] === name);
  return hasVisual[name] || merged.some((m) => hasVisual[m]);
}

for (const name of data.links) {
  if (hasVisualOrMerged(name)) continue;
  if (data.shapes[name]) {
    for (const shape of data.shapes[name]) {
      const geometry = shapeGeometry(shape);
      if (!geometry) continue;
      const mesh = new THREE.Mesh(geometry, shapeMaterial);
      mesh.position.fromArray(shape.position);
      mesh.quaternion.copy(basis(shape.axes));
      linkObjects[name].add(mesh);
      state.shapeCount += 1;
      state.shapeTypes[shape.type] = (state.shapeTypes[shape.type] || 0) + 1;
    }
    continue;
  }
  const box = data.boxes[name];
  if (!box) continue;
  const mesh = new THREE.Mesh(new THREE.BoxGeometry(box.size[0], box.size[1], box.size[2]),
                              boxMaterial);
  mesh.position.fromArray(box.center);
  mesh.quaternion.copy(basis(box.axes));  // the box's sides along the principal axes
  linkObjects[name].add(mesh);
  state.boxCount += 1;
}

const linkIndex = Object.fromEntries(data.links.map((n, i) => [n, i]));
function poseAt(frame, link) {
  const o = (frame * linkCount + link) * 7;
  return data.poses.slice(o, o + 7);
}

// The robot's size over the run, for the camera, the markers and the frames.
const bounds = new THREE.Box3();
for (let f = 0; f < frames; f += Math.max(1, Math.floor(frames / 50))) {
  for (let l = 0; l < linkCount; ++l) bounds.expandByPoint(new THREE.Vector3(...poseAt(f, l)));
}
for (const name of data.links) {
  const p = poseAt(0, linkIndex[name]);
  linkObjects[name].position.set(p[0], p[1], p[2]);
  linkObjects[name].quaternion.set(p[4], p[5], p[6], p[3]);
}
scene.updateMatrixWorld(true);
for (const o of Object.values(linkObjects)) bounds.expandByObject(o);
const size = Math.max(bounds.getSize(new THREE.Vector3()).length(), 0.1);
const center = bounds.getCenter(new THREE.Vector3());
camera.position.copy(center).add(new THREE.Vector3(1.0, -1.4, 0.8).multiplyScalar(size * 0.75));
camera.near = size / 500;
camera.far = size * 50;
orbit.target.copy(center);
orbit.update();
// The run's ground, n . x = height: a plane with a grid, centred under the robot (the point of the
// plane nearest the run's centre) and much larger than it; else a grid under the robot.
if (data.ground) {
  const n = new THREE.Vector3(...data.ground.normal).normalize();
  const at = center.clone().addScaledVector(n, data.ground.height - n.dot(center));
  const extent = Math.max(size * 6, 10);
  // The plane's depth is pushed back (polygon offset) so that the grid on it always shows.
  const plane = new THREE.Mesh(new THREE.PlaneGeometry(extent, extent),
                               new THREE.MeshPhongMaterial({
                                 color: 0xd8e4d0, side: THREE.DoubleSide, polygonOffset: true,
                                 polygonOffsetFactor: 1, polygonOffsetUnits: 1 }));
  // PlaneGeometry faces +z, GridHelper lies in the x-z plane (normal +y).
  plane.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), n);
  plane.position.copy(at);
  const groundGrid = new THREE.GridHelper(extent, 40, 0x99aa99, 0xb8c4b0);
  groundGrid.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), n);
  groundGrid.position.copy(at);
  scene.add(plane, groundGrid);
  state.ground = true;
} else {
  const grid = new THREE.GridHelper(size * 1.5, 15, 0xbbbbbb, 0xdddddd);
  grid.rotation.x = Math.PI / 2;
  grid.position.set(center.x, center.y, bounds.min.z);
  scene.add(grid);
}

// Joint markers coloured by |force| / max_force (green 0 to red 1), frames and axes on demand.
// The three axes of a spherical joint share their link's marker, coloured by the largest ratio.
const jointMarkers = [];
const linkMarkers = {};
const frameHelpers = [];
for (const joint of data.joints) {
  const link = linkObjects[joint.link];
  if (!linkMarkers[joint.link]) {
    // Drawn over the links (joints sit inside them), under the marker below.
    const marker = new THREE.Mesh(new THREE.SphereGeometry(size * 0.015, 16, 12),
                                  new THREE.MeshBasicMaterial({ color: 0x00aa00, depthTest: false }));
    marker.renderOrder = 900;
    link.add(marker);
    linkMarkers[joint.link] = marker;
  }
  jointMarkers.push(linkMarkers[joint.link]);
  const axes = new THREE.AxesHelper(size * 0.08);
  const axis = new THREE.ArrowHelper(new THREE.Vector3(...joint.axis).normalize(),
                                     new THREE.Vector3(), size * 0.12, 0xaa00aa);
  for (const helper of [axes, axis]) {
    helper.visible = false;
    link.add(helper);
    frameHelpers.push(helper);
  }
}
// A marker in a colour nothing else has, at data.marker's origin (tests find it in screenshots).
if (data.marker) {
  const m = new THREE.Mesh(new THREE.SphereGeometry(size * 0.012, 16, 12),
                           new THREE.MeshBasicMaterial({ color: 0xff00ff, depthTest: false }));
  m.renderOrder = 1000;
  linkObjects[data.marker].add(m);
}

// Contact forces: per frame an arrow for each link the ground pushed, from the average of its
// contact points along the force, |f| * per_newton long (1 m for the robot's weight), drawn over
// the links; one arrow per link, reused from frame to frame.
const contactArrows = new Map();
function contactArrow(link) {
  if (!contactArrows.has(link)) {
    const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 1,
                                        0xff5500);
    for (const part of [arrow.line, arrow.cone]) {
      part.material.depthTest = false;
      part.renderOrder = 950;
    }
    scene.add(arrow);
    contactArrows.set(link, arrow);
  }
  return contactArrows.get(link);
}

function showContacts(frame) {
  for (const arrow of contactArrows.values()) arrow.visible = false;
  state.contactArrows = 0;
  if (!data.contacts || !contactsBox.checked) return;
  const flat = data.contacts.frames[frame];
  for (let k = 0; k + 6 < flat.length; k += 7) {
    const force = new THREE.Vector3(flat[k + 4], flat[k + 5], flat[k + 6]);
    const length = force.length() * data.contacts.per_newton;
    if (!(length > 0)) continue;
    const arrow = contactArrow(flat[k]);
    arrow.position.set(flat[k + 1], flat[k + 2], flat[k + 3]);
    arrow.setDirection(force.normalize());
    const head = Math.min(0.3 * length, 0.05 * size);
    arrow.setLength(length, head, 0.6 * head);
    arrow.visible = true;
    state.contactArrows += 1;
  }
}

function forceRatio(joint, frame) {
  if (!joint.force) return 0;
  const scale = joint.max_force || joint.largest_force;
  return scale > 0 ? Math.min(1, Math.abs(joint.force[frame]) / scale) : 0;
}

// ---- curves -----------------------------------------------------------------------------------
const rowHeight = 70;
const margin = { left: 8, right: 8, top: 16, bottom: 6 };
const cursorColour = 'rgb(0, 255, 255)';
let curvesImage = null;
let plotBox = null;  // the x range of both columns, in CSS pixels

function drawSeries(ctx, x0, width, top, height, values, lo, hi, colour, dash) {
  if (!values) return;
  ctx.strokeStyle = colour;
  ctx.setLineDash(dash || []);
  ctx.beginPath();
  for (let k = 0; k < frames; ++k) {
    const x = x0 + (frames > 1 ? k / (frames - 1) : 0) * width;
    const y = top + height - ((values[k] - lo) / (hi - lo || 1)) * height;
    if (k === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
  }
  ctx.stroke();
  ctx.setLineDash([]);
}

function range(...series) {
  let lo = Infinity, hi = -Infinity;
  for (const s of series) if (s) for (const v of s) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  if (!(hi > lo)) { lo -= 1; hi += 1; }
  return [lo, hi];
}

function drawCurves() {
  const ratio = window.devicePixelRatio || 1;
  const width = curves.clientWidth;
  const height = Math.max(1, data.joints.length) * rowHeight;
  curves.width = Math.round(width * ratio);
  curves.height = Math.round(height * ratio);
  curves.style.height = height + 'px';
  const ctx = curves.getContext('2d');
  ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, width, height);
  const column = (width - margin.left - margin.right - 16) / 2;
  plotBox = { left: margin.left, column, gap: 16 };
  ctx.font = '11px sans-serif';
  data.joints.forEach((joint, j) => {
    const top = j * rowHeight + margin.top;
    const h = rowHeight - margin.top - margin.bottom;
    const [qlo, qhi] = range(joint.q, joint.target);
    const flimit = joint.max_force || joint.largest_force || 1;
    const xf = margin.left + column + 16;
    ctx.strokeStyle = '#ccc';
    ctx.strokeRect(margin.left, top, column, h);
    ctx.strokeRect(xf, top, column, h);
    drawSeries(ctx, margin.left, column, top, h, joint.q, qlo, qhi, '#1f5fbf');
    drawSeries(ctx, margin.left, column, top, h, joint.target, qlo, qhi, '#e07b00', [4, 3]);
    drawSeries(ctx, xf, column, top, h, joint.force, -flimit, flimit, '#2a9d2a');
    ctx.fillStyle = '#222';
    ctx.fillText(`${joint.name}: q (blue), target (orange) in [${qlo.toPrecision(3)}, ` +
                 `${qhi.toPrecision(3)}]`, margin.left, top - 4);
    ctx.fillText(`drive force in ±${flimit.toPrecision(3)}` +
                 (joint.max_force ? ' (max_force)' : ' (largest |force|)'), xf, top - 4);
  });
  curvesImage = ctx.getImageData(0, 0, curves.width, curves.height);
}

function drawCursor() {
  const ctx = curves.getContext('2d');
  ctx.putImageData(curvesImage, 0, 0);
  const u = frames > 1 ? state.frame / (frames - 1) : 0;
  ctx.fillStyle = cursorColour;
  for (const x0 of [plotBox.left, plotBox.left + plotBox.column + plotBox.gap]) {
    ctx.fillRect(Math.round(x0 + u * plotBox.column) - 1, 0, 2, curves.clientHeight);
  }
}

// ---- time -------------------------------------------------------------------------------------
function setFrame(frame) {
  state.frame = Math.max(0, Math.min(frames - 1, Math.round(frame)));
  state.time = data.times[state.frame];
  for (const name of data.links) {
    const p = poseAt(state.frame, linkIndex[name]);
    linkObjects[name].position.set(p[0], p[1], p[2]);
    linkObjects[name].quaternion.set(p[4], p[5], p[6], p[3]);
  }
  const ratios = new Map();
  data.joints.forEach((joint, j) => {
    const marker = jointMarkers[j];
    ratios.set(marker, Math.max(ratios.get(marker) || 0, forceRatio(joint, state.frame)));
  });
  ratios.forEach((ratio, marker) => marker.material.color.setRGB(ratio, 0.67 * (1 - ratio), 0));
  showContacts(state.frame);
  slider.value = String(state.frame);
  clock.textContent = `t = ${state.time.toFixed(3)} s (step ${state.frame} of ${frames - 1})`;
  drawCursor();
  render();
}

function resize() {
  if (renderer) {
    const width = view.clientWidth, height = view.clientHeight;
    renderer.setSize(width, height, false);
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
  }
  drawCurves();
}

function render() {
  if (!renderer) return;
  renderer.render(scene, camera);
  // The matrices the frame was drawn with (column-major, three.js's) and the canvas in CSS pixels.
  state.projection = camera.projectionMatrix.toArray();
  state.view = camera.matrixWorldInverse.toArray();
  const r = view.getBoundingClientRect();
  state.viewport = [r.left, r.top, r.width, r.height];
}

// The frame at run time t: the last with times[k] <= t.
function frameAt(t) {
  let lo = 0, hi = frames - 1;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (data.times[mid] <= t) lo = mid; else hi = mid - 1;
  }
  return lo;
}

let playClock = 0, lastTick = null;
function tick(now) {
  if (state.playing) {
    if (lastTick !== null) playClock += ((now - lastTick) / 1000) * Number(speed.value);
    const end = data.times[frames - 1];
    if (playClock > end) playClock = data.times[0];
    lastTick = now;
    setFrame(frameAt(playClock));
  } else {
    lastTick = null;  // nothing to draw: frames are drawn when something changes
  }
  requestAnimationFrame(tick);
}

function setPlaying(playing) {
  state.playing = playing && frames > 1;
  playButton.textContent = state.playing ? 'pause' : 'play';
  playClock = data.times[state.frame];
}

playButton.addEventListener('click', () => setPlaying(!state.playing));
slider.addEventListener('input', () => { setPlaying(false); setFrame(Number(slider.value)); });
framesBox.addEventListener('change', () => {
  for (const h of frameHelpers) h.visible = framesBox.checked;
  render();
});
contactsBox.addEventListener('change', () => setFrame(state.frame));
window.addEventListener('resize', () => { resize(); setFrame(state.frame); });

function contactLegend() {
  if (!data.contacts || !(data.contacts.per_newton > 0)) return '';
  const newtons = Number((1 / data.contacts.per_newton).toPrecision(4));
  return `Orange arrows: the ground's force on each link, 1 m per ${newtons} N. `;
}
legend.textContent = `${data.title}: ${frames} frames, dt ${Number(data.dt.toPrecision(6))} s. Joint spheres: |drive ` +
  'force| / max_force from green (0) to red (1; the run\'s largest |force| where a drive has no ' +
  'max_force). ' + contactLegend() + 'Drag to orbit, scroll to zoom.';
state.setFrame = setFrame;
state.setPlaying = setPlaying;
state.linkNames = data.links;
resize();
setFrame(0);
state.ready = true;
requestAnimationFrame(tick);
