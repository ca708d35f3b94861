// finestep view (docs/view.md): the scene from /scene.json (the planner's path and the
// positions of the period records, as `finestep` computed them) and the live state from
// /state.json, polled while a run goes on. Nothing here recomputes the path: it draws
// what the server sends, and writes what it drew into #figures for the browser test.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const POLL_MS = 200;
const BACKGROUND = 0x12161b;
const el = (id) => document.getElementById(id);
const figures = el('figures');
const started = performance.now();

const container = el('canvas');
// ?size=WxH fixes the canvas's size (the browser test: a screenshot's window and a DOM
// dump's differ in height, and the probes must land on the same pixels in both).
const fixedSize = new URLSearchParams(location.search).get('size');
if (fixedSize && /^\d+x\d+$/.test(fixedSize)) {
  const [w, h] = fixedSize.split('x');
  Object.assign(container.style, { width: `${w}px`, height: `${h}px`, right: 'auto', bottom: 'auto' });
}
const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setClearColor(BACKGROUND);
container.appendChild(renderer.domElement);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1e6);
camera.up.set(0, 0, 1); // Z up, as on the machine
const controls = new OrbitControls(camera, renderer.domElement);
controls.addEventListener('change', render);

function render() {
  renderer.render(scene, camera);
}

function resize() {
  const w = container.clientWidth, h = container.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
  render();
}
window.addEventListener('resize', resize);

// Feed to colour: blue at rest, red at the fastest feed of the program.
function feedColours(feed, feedMax) {
  const colours = new Float32Array(feed.length * 3);
  const c = new THREE.Color();
  for (let i = 0; i < feed.length; i++) {
    const f = feedMax > 0 ? Math.min(Math.max(feed[i] / feedMax, 0), 1) : 0;
    c.setHSL((1 - f) * 2 / 3, 0.9, 0.55);
    colours.set([c.r, c.g, c.b], 3 * i);
  }
  return colours;
}

function polyline(points, colours, opacity) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(points, 3));
  const material = new THREE.LineBasicMaterial({ vertexColors: colours !== null, color: colours ? 0xffffff : 0xffffff,
                                                  transparent: opacity < 1, opacity });
  if (colours) geometry.setAttribute('color', new THREE.Float32BufferAttribute(colours, 3));
  geometry.computeBoundingBox();
  return new THREE.Line(geometry, material);
}

let data = null;
let executed = null, programmed = null, trail = null;
let trailPoints = [];
const marker = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: 0xffd33d }));
const machine = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: 0xffffff }));
let liveUpdates = 0;
let lastPeriod = -1;

function fmt(v, digits = 3) {
  return Number(v).toFixed(digits);
}

// The executed path up to period `period`: draw range, the marker, time and line.
function scrubTo(period) {
  const tags = data.executed.tag;
  let lo = 0, hi = tags.length - 1;
  while (lo < hi) { // the last point at or before `period`
    const mid = (lo + hi + 1) >> 1;
    if (tags[mid] <= period) lo = mid; else hi = mid - 1;
  }
  executed.geometry.setDrawRange(0, lo + 1);
  const p = data.executed.points;
  marker.position.set(p[3 * lo], p[3 * lo + 1], p[3 * lo + 2]);
  el('time').textContent = fmt(period * data.period_s);
  el('line').textContent = data.executed_lines[lo];
  figures.dataset.scrubPeriod = period;
  render();
}

function project(x, y, z) {
  const v = new THREE.Vector3(x, y, z).project(camera);
  const rect = renderer.domElement.getBoundingClientRect();
  return [Math.round(rect.left + (v.x + 1) / 2 * rect.width), Math.round(rect.top + (1 - v.y) / 2 * rect.height)];
}

function build(sceneData) {
  data = sceneData;
  el('title').textContent = 'finestep view: ' + data.name;
  const feedMax = data.feed_max;
  el('feedmax').textContent = fmt(feedMax, 1);
  programmed = polyline(data.programmed.points, feedColours(data.programmed.feed, feedMax), 0.35);
  executed = polyline(data.executed.points, feedColours(data.executed.feed, feedMax), 1);
  trail = polyline(new Float32Array(0), null, 1);
  scene.add(programmed, executed, trail, marker, machine);

  const [lo, hi] = data.bbox;
  const box = new THREE.Box3(new THREE.Vector3(...lo), new THREE.Vector3(...hi));
  const size = box.getSize(new THREE.Vector3());
  const centre = box.getCenter(new THREE.Vector3());
  const span = Math.max(size.x, size.y, size.z, 1e-3);
  marker.scale.setScalar(span / 120);
  machine.scale.setScalar(span / 150);
  const grid = new THREE.GridHelper(span * 1.2, 12, 0x3a4452, 0x262d36);
  grid.rotation.x = Math.PI / 2; // in the X-Y plane
  grid.position.set(centre.x, centre.y, lo[2]);
  scene.add(grid, new THREE.AxesHelper(span / 5));
  camera.near = span / 1000;
  camera.far = span * 100;
  camera.position.set(centre.x + span * 0.9, centre.y - span * 1.3, centre.z + span * 0.9);
  controls.target.copy(centre);
  controls.update();
  resize();

  const scrub = el('scrub');
  scrub.max = data.periods;
  scrub.value = data.periods;
  scrub.addEventListener('input', () => {
    el('follow').checked = false;
    scrubTo(Number(scrub.value));
  });
  for (const [id, object] of [['show-programmed', programmed], ['show-executed', executed], ['show-trail', trail]]) {
    el(id).addEventListener('change', (e) => { object.visible = e.target.checked; render(); });
  }
  scrubTo(data.periods);

  // What was drawn, from the drawn geometry itself.
  const drawn = new THREE.Box3().copy(programmed.geometry.boundingBox).union(executed.geometry.boundingBox);
  figures.dataset.programmedSegments = programmed.geometry.attributes.position.count - 1;
  figures.dataset.executedSegments = executed.geometry.attributes.position.count - 1;
  figures.dataset.bbox = JSON.stringify([drawn.min.toArray(), drawn.max.toArray()]);
  figures.dataset.periods = data.periods;
  // Where some of the executed path lands on the screen, for the screenshot check.
  const probes = [];
  const n = data.executed.points.length / 3;
  for (let k = 0; k < 8; k++) {
    const i = Math.floor((k + 0.5) / 8 * n);
    const p = data.executed.points;
    probes.push(project(p[3 * i], p[3 * i + 1], p[3 * i + 2]));
  }
  figures.dataset.probes = JSON.stringify(probes);
  figures.dataset.canvas = JSON.stringify([renderer.domElement.clientWidth, renderer.domElement.clientHeight]);
}

function showState(state) {
  liveUpdates += 1;
  el('source').textContent = state.source;
  el('state').textContent = state.running ? 'running' : state.done ? 'done' : 'waiting';
  const share = state.periods > 0 ? 100 * state.period / state.periods : 100;
  el('progress').textContent = `${state.period} / ${state.periods} periods (${fmt(share, 1)} %)`;
  el('position').textContent = state.position.map((v) => fmt(v)).join(', ');
  el('fifo').textContent = state.fifo ? `${state.fifo[0]} records, ${state.fifo[1]} free` : 'none (no chip)';
  el('underruns').textContent = state.underruns;
  if (state.errors.length) el('errors').textContent = state.errors.join('\n');
  machine.position.set(...state.position);
  for (const p of state.trail) trailPoints.push(p[0], p[1], p[2]);
  if (state.trail.length) {
    trail.geometry.setAttribute('position', new THREE.Float32BufferAttribute(trailPoints, 3));
    trail.geometry.computeBoundingSphere();
  }
  if (el('follow').checked) {
    el('scrub').value = state.period;
    scrubTo(state.period);
  } else {
    render();
  }
  if (state.period < lastPeriod) noteError(`the live period went back from ${lastPeriod} to ${state.period}`);
  lastPeriod = state.period;
  Object.assign(figures.dataset, {
    liveUpdates, livePeriod: state.period, liveDone: state.done, liveRunning: state.running,
    livePosition: JSON.stringify(state.position), liveUnderruns: state.underruns,
    liveErrors: JSON.stringify(state.errors), trailPoints: trailPoints.length / 3,
  });
  if (!figures.dataset.firstLivePeriod) figures.dataset.firstLivePeriod = state.period;
  return state.done;
}

function noteError(text) {
  window.viewErrors.push(String(text));
  figures.dataset.errors = JSON.stringify(window.viewErrors);
  el('errors').textContent = window.viewErrors.join('\n');
}

async function poll() {
  try {
    const response = await fetch(`/state.json?since=${trailPoints.length / 3}`, { cache: 'no-store' });
    if (!response.ok) throw new Error(`/state.json: HTTP ${response.status}`);
    if (showState(await response.json())) return;
  } catch (e) {
    // The run's process has ended (its server with it): keep what was shown.
    el('state').textContent = 'no answer: ' + e.message;
    return;
  }
  setTimeout(poll, POLL_MS);
}

async function main() {
  const response = await fetch('/scene.json');
  if (!response.ok) throw new Error(`/scene.json: HTTP ${response.status}`);
  build(await response.json());
  figures.dataset.loadMs = Math.round(performance.now() - started);
  figures.dataset.ready = '1';
  await poll();
}

main().catch((e) => noteError(e.stack || e));
