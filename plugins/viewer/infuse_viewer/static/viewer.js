// infuse viewer: one or more GLB characters, their clips, audio, skeleton mapping and targets.
// Page data (id "infuse-data"): {mode: "served"|"offline", entries: [...]}; see infuse_viewer/page.py.
// Scene units are the glTF file's: metres, +Y up.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const DATA = JSON.parse(document.getElementById('infuse-data').textContent);
const $ = (id) => document.getElementById(id);
const COLORS = { mapped: 0x35d0b5, low: 0xff7a45, unmapped: 0x8b93a5, bone: 0xdfe6f2, boneOverlay: 0xbfe9ff,
  gaze: 0xffd166, reach: 0x7bd88f, point: 0x4cc9f0 };

// Test and scripting hooks: ready turns true once the first file is shown.
const api = window.infuseViewer = { ready: false, error: null, frame: 0 };

// ---------------------------------------------------------------- data sources
function blobBytes(id) {
  const text = $(id).textContent.trim();
  if (Uint8Array.fromBase64) return Uint8Array.fromBase64(text);
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
  return bytes;
}
const blobUrls = new Map();
function blobUrl(id) {
  if (!blobUrls.has(id)) blobUrls.set(id, URL.createObjectURL(new Blob([blobBytes(id)], { type: $(id).dataset.type })));
  return blobUrls.get(id);
}
async function fetchChecked(url, kind) {
  const response = await fetch(url);
  if (!response.ok) {
    let detail = '';
    try { detail = (await response.json()).error; } catch (e) { detail = response.statusText; }
    throw new Error(detail || `${kind}: HTTP ${response.status}`);
  }
  return response;
}
async function loadSource(entry) {
  if (DATA.mode === 'offline') {
    const audio = {};
    for (const [key, id] of Object.entries(entry.info.audio)) audio[key] = blobUrl(id);
    return { info: entry.info, glb: blobBytes(entry.glb).buffer, audio };
  }
  const info = await (await fetchChecked(entry.info_url, 'info')).json();
  const glb = await (await fetchChecked(entry.glb_url, 'model')).arrayBuffer();
  return { info, glb, audio: info.audio };
}

// ---------------------------------------------------------------- scene
const canvas = $('view');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
renderer.toneMapping = THREE.ACESFilmicToneMapping;
renderer.toneMappingExposure = 1.05;
renderer.shadowMap.enabled = true;
renderer.shadowMap.type = THREE.PCFShadowMap;

const scene = new THREE.Scene();
scene.background = new THREE.Color(0x1d2129);
scene.fog = new THREE.Fog(0x1d2129, 10, 40);
const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 1000);
const controls = new OrbitControls(camera, canvas);
controls.enableDamping = true;

const hemi = new THREE.HemisphereLight(0xe8efff, 0x4a4036, 1.6);
scene.add(hemi);
const key = new THREE.DirectionalLight(0xffffff, 2.4);
key.castShadow = true;
key.shadow.mapSize.set(1024, 1024);
key.shadow.bias = -0.0005;
scene.add(key, key.target);
const rim = new THREE.DirectionalLight(0x9ec9ff, 1.1);
scene.add(rim, rim.target);

const groundGroup = new THREE.Group();
scene.add(groundGroup);

// ---------------------------------------------------------------- state
const state = {
  entryIndex: -1, info: null, audio: {}, root: null, mixer: null, clips: [], clip: null, action: null,
  time: 0, duration: 0, playing: false, hasMesh: false, joints: [], bones: [], targets: [], height: 1.7,
  rootJoint: null, follow: false,
};
let dirty = true;  // the next animation frame draws
const audio = new Audio();
audio.preload = 'auto';
let audioBlocked = false;

// ---------------------------------------------------------------- skeleton overlay
const overlay = { group: new THREE.Group(), bones: null, spheres: null };
scene.add(overlay.group);
const unitCylinder = new THREE.CylinderGeometry(1, 1, 1, 10, 1).translate(0, 0.5, 0);
const unitSphere = new THREE.SphereGeometry(1, 16, 12);
const tmp = { a: new THREE.Vector3(), b: new THREE.Vector3(), d: new THREE.Vector3(), q: new THREE.Quaternion(),
  s: new THREE.Vector3(), m: new THREE.Matrix4(), up: new THREE.Vector3(0, 1, 0), c: new THREE.Color() };

function disposeGroup(group) {
  group.traverse((o) => {
    if (o.isInstancedMesh) o.dispose();
    if (o.geometry && o.geometry !== unitCylinder && o.geometry !== unitSphere) o.geometry.dispose();
    if (o.material) [].concat(o.material).forEach((m) => m.dispose());
  });
  group.clear();
}

function buildOverlay() {
  disposeGroup(overlay.group);
  const onTop = state.hasMesh;
  const joints = state.joints;
  // a link that stretches over a clip (e.g. a BVH root left at the origin) is no bone: not drawn
  state.bones = joints.filter((j) => j.parent >= 0 && !j.free && j.object && joints[j.parent].object).map((j) => [j.parent, j.index]);
  const linked = new Set(state.bones.flat());
  for (const j of joints) j.hidden = !j.object || (state.bones.length > 0 && !linked.has(j.index));
  state.rootJoint = joints.find((j) => !j.hidden) || null;
  const boneMat = onTop
    ? new THREE.MeshBasicMaterial({ color: COLORS.boneOverlay, transparent: true, opacity: 0.55, depthTest: false, depthWrite: false })
    : new THREE.MeshStandardMaterial({ color: COLORS.bone, roughness: 0.55, metalness: 0.05 });
  const jointMat = onTop
    ? new THREE.MeshBasicMaterial({ transparent: true, opacity: 0.95, depthTest: false, depthWrite: false })
    : new THREE.MeshStandardMaterial({ roughness: 0.4, metalness: 0.05 });
  overlay.bones = new THREE.InstancedMesh(unitCylinder, boneMat, Math.max(state.bones.length, 1));
  overlay.bones.count = state.bones.length;
  overlay.spheres = new THREE.InstancedMesh(unitSphere, jointMat, Math.max(joints.length, 1));
  overlay.spheres.count = joints.length;
  for (const j of joints) overlay.spheres.setColorAt(j.index, tmp.c.set(jointColor(j)));
  for (const mesh of [overlay.bones, overlay.spheres]) {
    mesh.frustumCulled = false;
    mesh.renderOrder = onTop ? 10 : 0;
    mesh.castShadow = !onTop;
  }
  overlay.group.add(overlay.bones, overlay.spheres);
}

function jointColor(j) {
  if (j.low) return COLORS.low;
  return j.canonical.length ? COLORS.mapped : COLORS.unmapped;
}

function updateOverlay() {
  const joints = state.joints;
  for (const j of joints) if (j.object) j.object.getWorldPosition(j.world);
  const h = state.height;
  const boneRadius = h * (state.hasMesh ? 0.004 : 0.0075);
  const jointRadius = h * (state.hasMesh ? 0.009 : 0.0095);
  state.bones.forEach(([p, c], k) => {
    tmp.a.copy(joints[p].world);
    tmp.d.subVectors(joints[c].world, tmp.a);
    const length = tmp.d.length();
    tmp.q.setFromUnitVectors(tmp.up, length > 1e-9 ? tmp.d.divideScalar(length) : tmp.up);
    tmp.m.compose(tmp.a, tmp.q, tmp.s.set(boneRadius, length, boneRadius));
    overlay.bones.setMatrixAt(k, tmp.m);
  });
  for (const j of joints) {
    const r = j.hidden ? 0 : j.tip ? jointRadius * 0.6 : j.low ? jointRadius * 1.7 : j === hovered ? jointRadius * 1.6 : jointRadius;
    tmp.m.compose(j.world, tmp.q.identity(), tmp.s.set(r, r, r));
    overlay.spheres.setMatrixAt(j.index, tmp.m);
  }
  overlay.bones.instanceMatrix.needsUpdate = true;
  overlay.spheres.instanceMatrix.needsUpdate = true;
}

// ---------------------------------------------------------------- targets
const targetGroup = new THREE.Group();
scene.add(targetGroup);

function buildTargets(list) {
  disposeGroup(targetGroup);
  state.targets = list.map((t) => {
    const color = COLORS[t.kind];
    const r = state.height * 0.025;
    const marker = new THREE.Group();
    const core = new THREE.Mesh(new THREE.SphereGeometry(r, 20, 14), new THREE.MeshStandardMaterial({ color, emissive: color, emissiveIntensity: 0.5 }));
    marker.add(core);
    if (t.kind === 'gaze') {
      const ring = new THREE.Mesh(new THREE.TorusGeometry(r * 2.2, r * 0.25, 8, 32), new THREE.MeshBasicMaterial({ color }));
      marker.add(ring);
      marker.userData.ring = ring;
    } else if (t.kind === 'reach') {
      const cross = new THREE.Mesh(new THREE.OctahedronGeometry(r * 2.0), new THREE.MeshBasicMaterial({ color, wireframe: true }));
      marker.add(cross);
    }
    targetGroup.add(marker);
    const from = t.from ? state.joints.find((j) => j.canonical.includes(t.from)) : null;
    let line = null;
    if (from) {
      const geometry = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]);
      line = new THREE.Line(geometry, new THREE.LineDashedMaterial({ color, dashSize: state.height * 0.03, gapSize: state.height * 0.02 }));
      line.frustumCulled = false;
      targetGroup.add(line);
    }
    const label = document.createElement('div');
    label.className = `target ${t.kind}`;
    label.textContent = t.name;
    return { ...t, marker, line, from, label, position: new THREE.Vector3() };
  });
}

function targetPosition(t, time, out) {
  const ts = t.times, ps = t.positions;
  if (time <= ts[0] || ts.length === 1) return out.fromArray(ps[0]);
  if (time >= ts[ts.length - 1]) return out.fromArray(ps[ps.length - 1]);
  let k = 1;
  while (ts[k] < time) k++;
  const w = (time - ts[k - 1]) / (ts[k] - ts[k - 1]);
  return out.fromArray(ps[k - 1]).lerp(tmp.b.fromArray(ps[k]), w);
}

function updateTargets() {
  for (const t of state.targets) {
    targetPosition(t, state.time, t.position);
    t.marker.position.copy(t.position);
    if (t.marker.userData.ring) t.marker.userData.ring.lookAt(camera.position);
    if (t.line) {
      const attr = t.line.geometry.attributes.position;
      attr.setXYZ(0, t.from.world.x, t.from.world.y, t.from.world.z);
      attr.setXYZ(1, t.position.x, t.position.y, t.position.z);
      attr.needsUpdate = true;
      t.line.computeLineDistances();
    }
  }
}

// ---------------------------------------------------------------- labels and hover
const labelLayer = $('labels');
const tip = $('tip');
let hovered = null;
let pointer = null;

function project(v) {
  const p = tmp.b.copy(v).project(camera);
  const rect = canvas.getBoundingClientRect();
  return { x: (p.x + 1) / 2 * rect.width + rect.left, y: (1 - p.y) / 2 * rect.height + rect.top, visible: p.z < 1 };
}

function jointsOnScreen() {
  return state.joints.filter((j) => !j.hidden && !j.tip).map((j) => ({ joint: j, ...project(j.world) }));
}

function updateHover() {
  hovered = null;
  if (pointer && $('show-skeleton').checked) {
    let best = 12 * 12;
    for (const s of jointsOnScreen()) {
      const d = (s.x - pointer.x) ** 2 + (s.y - pointer.y) ** 2;
      if (s.visible && d < best) { best = d; hovered = s.joint; }
    }
  }
  if (!hovered) { tip.hidden = true; return; }
  const j = hovered;
  tip.className = j.low ? 'low' : '';
  const names = j.canonical.length ? j.canonical.join(', ') : 'no canonical name';
  const conf = j.confidence === null ? '' : ` · confidence ${j.confidence.toFixed(2)}`;
  tip.innerHTML = '';
  const head = document.createElement('div');
  const b = document.createElement('b'); b.textContent = names; head.append(b, document.createTextNode(conf));
  const joint = document.createElement('div'); joint.textContent = `joint ${j.name}`;
  tip.append(head, joint);
  if (j.reason) { const r = document.createElement('div'); r.className = 'reason'; r.textContent = j.reason; tip.append(r); }
  tip.style.left = `${pointer.x + 14}px`;
  tip.style.top = `${pointer.y + 14}px`;
  tip.hidden = false;
}

// Target labels always show; joint names are placed low-confidence first, then root first, and
// left out where they would cover a label already placed (fingers crowd).
function updateLabels() {
  const wanted = [];
  if ($('show-targets').checked) for (const t of state.targets) wanted.push([t.label, t.position, true]);
  if ($('show-names').checked && $('show-skeleton').checked) {
    const named = state.joints.filter((j) => j.label && !j.hidden);
    for (const j of [...named.filter((j) => j.low), ...named.filter((j) => !j.low)]) wanted.push([j.label, j.world, false]);
  }
  const keep = new Set();
  const placed = [];
  for (const [el, pos, always] of wanted) {
    const p = project(pos);
    if (!p.visible) continue;
    el.style.left = `${p.x}px`;
    el.style.top = `${p.y}px`;
    if (el.parentNode !== labelLayer) labelLayer.append(el);
    keep.add(el);
    const w = el.offsetWidth, h = el.offsetHeight;
    const box = { l: p.x - w / 2, r: p.x + w / 2, t: p.y - 1.3 * h, b: p.y - 0.3 * h };
    const covers = placed.some((o) => box.l < o.r && o.l < box.r && box.t < o.b && o.t < box.b);
    el.style.visibility = covers && !always ? 'hidden' : '';
    if (!covers || always) placed.push(box);
  }
  for (const el of [...labelLayer.children]) if (!keep.has(el)) el.remove();
}

canvas.addEventListener('pointermove', (e) => { pointer = { x: e.clientX, y: e.clientY }; });
canvas.addEventListener('pointerleave', () => { pointer = null; });

// ---------------------------------------------------------------- time and audio
function audioFor(clipName) {
  return state.audio[clipName] || state.audio['*'] || null;
}

function setAudioSource(clipName) {
  const src = audioFor(clipName);
  audio.pause();
  if (src) { if (audio.dataset.src !== src) { audio.src = src; audio.dataset.src = src; } } else { audio.removeAttribute('src'); audio.dataset.src = ''; audio.load(); }
  $('audio-state').textContent = src ? '♪ audio' : '';
}

function startAudio() {
  if (!audio.dataset.src || !state.playing) return;
  if (state.time >= (audio.duration || Infinity)) return;
  audio.currentTime = state.time;
  audio.playbackRate = Number($('speed').value);
  audio.play().then(() => { audioBlocked = false; $('audio-state').textContent = '♪ audio'; })
    .catch(() => { audioBlocked = true; $('audio-state').textContent = '♪ press play for sound'; });
}

function applyTime() {
  if (state.action) {
    state.action.time = state.time;
    state.mixer.update(0);
  }
  state.root?.updateMatrixWorld(true);
}

function setTime(t) {
  dirty = true;
  state.time = Math.min(Math.max(t, 0), state.duration);
  applyTime();
  if (audio.dataset.src) {
    if (state.playing && state.time < (audio.duration || Infinity)) { if (audio.paused) startAudio(); else audio.currentTime = state.time; }
    else audio.currentTime = Math.min(state.time, audio.duration || state.time);
  }
}

function play() {
  if (!state.action) return;
  if (state.time >= state.duration) setTime(0);
  state.playing = true;
  startAudio();
  refreshBar();
}

function pause() {
  dirty = true;
  state.playing = false;
  audio.pause();
  refreshBar();
}

function advance(dt) {
  if (!state.playing || !state.action) return;
  const speed = Number($('speed').value);
  const audioClock = audio.dataset.src && !audio.paused && !audio.ended && audio.currentTime < state.duration;
  let t = audioClock ? audio.currentTime : state.time + dt * speed;
  if (t >= state.duration) {
    if ($('loop').checked && state.duration > 0) {
      t = t % state.duration;
      state.time = t;
      applyTime();
      startAudio();
      return;
    }
    t = state.duration;
    state.playing = false;
    audio.pause();
  }
  state.time = t;
  applyTime();
  if (audio.dataset.src && !audio.paused && Math.abs(audio.currentTime - t) > 0.15) audio.currentTime = t;
}

// ---------------------------------------------------------------- UI
function fmt(t) { return t.toFixed(2); }

function refreshBar() {
  $('play').textContent = state.playing ? '❚❚' : '▶';
  $('play').setAttribute('aria-label', state.playing ? 'Pause' : 'Play');
  $('play').disabled = !state.action;
  $('timeline').disabled = !state.action;
  $('timeline').max = String(state.duration || 1);
  if (document.activeElement !== $('timeline') || state.playing) $('timeline').value = String(state.time);
  $('time').textContent = `${fmt(state.time)} / ${fmt(state.duration)} s`;
}

function listItem(name, meta, onClick) {
  const li = document.createElement('li');
  const n = document.createElement('span'); n.className = 'name'; n.textContent = name; n.title = name;
  li.append(n);
  if (meta) { const m = document.createElement('span'); m.className = 'meta'; m.textContent = meta; li.append(m); }
  if (onClick) li.addEventListener('click', onClick);
  return li;
}

function fillFiles() {
  const ul = $('files');
  ul.innerHTML = '';
  $('files-section').hidden = DATA.entries.length < 2;
  DATA.entries.forEach((e, i) => {
    const li = listItem(e.name, null, () => selectEntry(i).catch(showError));
    li.classList.toggle('active', i === state.entryIndex);
    ul.append(li);
  });
}

function fillClips() {
  const ul = $('clips');
  ul.innerHTML = '';
  for (const clip of state.clips) {
    const li = listItem(clip.name, `${fmt(clip.duration)} s`, () => selectClip(clip.name));
    li.dataset.clip = clip.name;
    li.classList.toggle('active', clip === state.clip);
    ul.append(li);
  }
  $('no-clips').hidden = state.clips.length > 0;
}

function fillMapping(info) {
  const m = info.mapping;
  const summary = $('mapping-summary');
  summary.className = 'note';
  const lowJoints = state.joints.filter((j) => j.low);
  if (m.error) { summary.textContent = `No mapping: ${m.error}`; summary.className = 'note error'; }
  else summary.textContent = `${m.mapped} of ${m.required} canonical joints mapped by ${m.mapper} ` +
    `(overall ${m.overall_confidence.toFixed(2)}); ${lowJoints.length} below ${m.low_confidence.toFixed(2)}.`;
  const ul = $('low-joints');
  ul.innerHTML = '';
  for (const j of lowJoints) {
    const li = listItem(j.canonical.join(', '), j.confidence.toFixed(2));
    li.title = `joint ${j.name}${j.reason ? ` — ${j.reason}` : ''}`;
    li.style.color = 'var(--low)';
    ul.append(li);
  }
  const missing = $('missing');
  missing.innerHTML = '';
  $('missing-box').hidden = !m.missing.length;
  $('missing-summary').textContent = `${m.missing.length} canonical names without a joint`;
  for (const x of m.missing) { const li = listItem(x.canonical, x.confidence.toFixed(2)); li.title = x.reason; missing.append(li); }
}

function fillTargets() {
  const ul = $('targets');
  ul.innerHTML = '';
  $('targets-section').hidden = !state.targets.length;
  for (const t of state.targets) {
    const li = listItem(t.name, t.times.length > 1 ? `${t.kind} track` : t.kind);
    const dot = document.createElement('i'); dot.className = `dot ${t.kind}`; li.firstChild.prepend(dot);
    ul.append(li);
  }
}

function applyVisibility() {
  const showSkeleton = $('show-skeleton').checked;
  overlay.group.visible = showSkeleton || !state.hasMesh;
  const offered = { 'show-mesh': state.hasMesh, 'show-skeleton': state.hasMesh,  // without a mesh the skeleton is the figure
    'show-targets': state.targets.length > 0, follow: state.clips.length > 0 };
  for (const [id, shown] of Object.entries(offered)) $(id).parentElement.style.display = shown ? '' : 'none';
  if (state.root) state.root.traverse((o) => { if (o.isMesh) o.visible = $('show-mesh').checked; });
  targetGroup.visible = $('show-targets').checked;
}
for (const id of ['show-mesh', 'show-skeleton', 'show-names', 'show-targets']) $(id).addEventListener('change', applyVisibility);
$('follow').addEventListener('change', () => { if (state.rootJoint) state.rootJoint.object.getWorldPosition(followAnchor); });
$('play').addEventListener('click', () => (state.playing ? pause() : play()));
$('timeline').addEventListener('input', (e) => { setTime(Number(e.target.value)); refreshBar(); });
$('speed').addEventListener('change', () => { audio.playbackRate = Number($('speed').value); });
window.addEventListener('keydown', (e) => {
  if (e.code === 'Space' && e.target === document.body) { e.preventDefault(); state.playing ? pause() : play(); }
  if (e.key === 'f' && e.target === document.body) frameCharacter();
});

// ---------------------------------------------------------------- framing
function poseBox(box) {
  for (const j of state.joints) if (!j.hidden) box.expandByPoint(j.object.getWorldPosition(tmp.a));
  if (state.hasMesh) {
    state.root.traverse((o) => {
      if (!o.isMesh || !o.visible) return;
      if (o.isSkinnedMesh) o.computeBoundingBox();
      else if (!o.geometry.boundingBox) o.geometry.computeBoundingBox();
      const b = (o.isSkinnedMesh ? o.boundingBox : o.geometry.boundingBox).clone().applyMatrix4(o.matrixWorld);
      if (isFinite(b.min.x) && isFinite(b.max.x)) box.union(b);
    });
  }
  return box;
}

// Boxes over the clip: `path` holds every sampled pose, `pose` the current one, `travel` the root's path.
function clipBoxes() {
  const path = new THREE.Box3();
  const travel = new THREE.Box3();
  const saved = state.time;
  const samples = state.action ? 8 : 1;
  for (let k = 0; k < samples; k++) {
    state.time = samples > 1 ? state.duration * k / (samples - 1) : 0;
    applyTime();
    poseBox(path);
    if (state.rootJoint) travel.expandByPoint(state.rootJoint.object.getWorldPosition(tmp.a));
  }
  state.time = saved;
  applyTime();
  const pose = poseBox(new THREE.Box3());
  if (path.isEmpty()) path.setFromObject(state.root);
  if (pose.isEmpty()) pose.copy(path);
  if (travel.isEmpty()) travel.expandByPoint(tmp.a.set(0, 0, 0));
  return { path, pose, travel };
}

// A ground grid drawn by a shader on a disc (minor lines every `step`, major every 5), fading out
// towards the rim; antialiased with screen-space derivatives, and clipped like any triangle.
function groundGrid(radius, step) {
  const material = new THREE.ShaderMaterial({
    transparent: true, depthWrite: false, side: THREE.DoubleSide,
    uniforms: { step: { value: step }, radius: { value: radius }, minor: { value: new THREE.Color(0x3a4252) },
      major: { value: new THREE.Color(0x5d6980) } },
    vertexShader: `varying vec2 vPlane;
      void main() { vPlane = position.xz; gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }`,
    fragmentShader: `uniform float step; uniform float radius; uniform vec3 minor; uniform vec3 major; varying vec2 vPlane;
      float lines(float size) {
        vec2 c = vPlane / size;
        vec2 d = abs(fract(c - 0.5) - 0.5) / fwidth(c);
        return 1.0 - min(min(d.x, d.y), 1.0);
      }
      void main() {
        float a = lines(step), b = lines(step * 5.0);
        float fade = 1.0 - smoothstep(radius * 0.45, radius, length(vPlane));
        gl_FragColor = vec4(mix(minor, major, b), max(a * 0.8, b) * fade);
      }`,
  });
  return new THREE.Mesh(new THREE.CircleGeometry(radius, 96).rotateX(-Math.PI / 2), material);
}

function niceStep(x) {
  const p = 10 ** Math.floor(Math.log10(x));
  const m = x / p;
  return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
}

// A figure that travels more than half its height over the clip is followed by the camera.
function frameCharacter() {
  const boxes = clipBoxes();
  const pathSize = boxes.path.getSize(new THREE.Vector3());
  const poseSize = boxes.pose.getSize(new THREE.Vector3());
  const travel = boxes.travel.getSize(new THREE.Vector3());
  state.follow = Math.max(travel.x, travel.z) > 0.5 * Math.max(poseSize.y, 1e-3);
  $('follow').checked = state.follow;
  followAnchor.copy(state.rootJoint ? state.rootJoint.object.getWorldPosition(tmp.a) : tmp.a.set(0, 0, 0));
  const box = boxes.path.clone();
  if (state.follow) box.set(box.min.setX(boxes.pose.min.x).setZ(boxes.pose.min.z), box.max.setX(boxes.pose.max.x).setZ(boxes.pose.max.z));
  const size = box.getSize(new THREE.Vector3());
  const center = box.getCenter(new THREE.Vector3());
  const height = Math.max(size.y, 0.25 * Math.max(size.x, size.z), 1e-3);
  resize();
  const free = freeAreaOffset(canvas.clientWidth, canvas.clientHeight);
  const tanHalf = Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2) / Math.max(canvas.clientHeight, 1);
  const fitH = (size.y / 2) / (tanHalf * free.height);
  const fitW = (Math.max(size.x, size.z) / 2) / (tanHalf * free.width);
  const distance = Math.max(fitH, fitW) * 1.35 + Math.max(size.x, size.z) / 2;
  const dir = new THREE.Vector3(Math.sin(0.5), 0.22, Math.cos(0.5)).normalize();  // front, a little to the character's left
  camera.position.copy(center).addScaledVector(dir, distance);
  camera.near = distance / 200;
  camera.far = distance * 50;
  camera.updateProjectionMatrix();
  controls.target.copy(center);
  controls.update();
  scene.fog.near = distance * 1.5;
  scene.fog.far = distance * 6;

  // ground: a grid whose cells suit the character's size, on its lowest point over the clip
  disposeGroup(groundGroup);
  const step = niceStep(height / 4);
  const ground = boxes.path.getCenter(new THREE.Vector3());
  const extent = Math.ceil((Math.max(pathSize.x, pathSize.z) / 2 + height * 3) / step) * step;
  const grid = groundGrid(extent, step);
  grid.position.set(ground.x, box.min.y, ground.z);
  const floor = new THREE.Mesh(new THREE.CircleGeometry(extent, 64).rotateX(-Math.PI / 2),
    new THREE.ShadowMaterial({ opacity: 0.32, depthWrite: false }));  // no depth: the grid lines on it stay whole
  floor.position.set(ground.x, box.min.y - height * 0.001, ground.z);
  floor.receiveShadow = true;
  groundGroup.add(floor, grid);

  key.position.copy(center).add(new THREE.Vector3(height * 1.2, height * 2.4, height * 1.8));
  key.target.position.copy(center);
  const s = Math.max(size.x, size.z, height) * 1.5;
  Object.assign(key.shadow.camera, { left: -s, right: s, top: s, bottom: -s, near: height * 0.1, far: height * 8 });
  key.shadow.camera.updateProjectionMatrix();
  rim.position.copy(center).add(new THREE.Vector3(-height * 1.5, height * 1.2, -height * 2));
  rim.target.position.copy(center);
}

// ---------------------------------------------------------------- loading
const loader = new GLTFLoader();

function parseGlb(buffer) {
  return new Promise((resolve, reject) => loader.parse(buffer, '', resolve, reject));
}

function clearCharacter() {
  pause();
  if (state.root) {
    scene.remove(state.root);
    state.root.traverse((o) => {
      if (o.geometry) o.geometry.dispose();
      if (o.material) [].concat(o.material).forEach((m) => { for (const v of Object.values(m)) if (v && v.isTexture) v.dispose(); m.dispose(); });
    });
  }
  for (const j of state.joints) j.label?.remove();
  for (const t of state.targets) t.label.remove();
  Object.assign(state, { root: null, mixer: null, clips: [], clip: null, action: null, time: 0, duration: 0, joints: [], bones: [], targets: [] });
}

async function selectEntry(index) {
  const entry = DATA.entries[index];
  const status = $('status');
  status.className = '';
  status.textContent = `Loading ${entry.name}…`;
  const { info, glb, audio: audioUrls } = await loadSource(entry);
  const gltf = await parseGlb(glb);
  clearCharacter();
  state.entryIndex = index;
  state.info = info;
  state.audio = audioUrls || {};
  state.root = gltf.scene;
  scene.add(state.root);
  state.hasMesh = false;
  state.root.traverse((o) => {
    if (o.isMesh) { state.hasMesh = true; o.castShadow = true; o.receiveShadow = true; if (o.isSkinnedMesh) o.frustumCulled = false; }
  });
  const byNode = new Map();
  gltf.parser.associations.forEach((value, object) => {
    if (value && value.nodes !== undefined && !byNode.has(value.nodes)) byNode.set(value.nodes, object);
  });
  state.joints = info.joints.map((j, index) => ({ ...j, index, object: byNode.get(j.node) || null, world: new THREE.Vector3() }));
  if (!info.joints.length) {  // the file could not be mapped: draw the glTF skin's bones
    const bones = [];
    state.root.traverse((o) => { if (o.isBone) bones.push(o); });
    state.joints = bones.map((o, index) => ({ node: -1, name: o.name, parent: bones.indexOf(o.parent), canonical: [], confidence: null,
      reason: '', low: false, index, object: o, world: new THREE.Vector3() }));
  }
  for (const j of state.joints) {
    if (!j.canonical.length) continue;
    j.label = document.createElement('div');
    j.label.textContent = j.canonical.join(', ');
    if (j.low) j.label.className = 'low';
  }
  state.height = Math.max(info.height_m || 0, 0.1);
  state.mixer = new THREE.AnimationMixer(state.root);
  state.clips = gltf.animations;
  $('file-name').textContent = info.file;
  document.title = `${info.name} · infuse view`;
  buildOverlay();
  buildTargets(info.targets);
  fillFiles();
  fillMapping(info);
  fillTargets();
  if (state.clips.length) selectClip(state.clips[0].name, true);
  else { setAudioSource(null); refreshBar(); fillClips(); }
  state.root.updateMatrixWorld(true);
  updateOverlay();
  frameCharacter();
  applyVisibility();
  dirty = true;
  status.textContent = '';
}

function selectClip(name, autoplay = state.playing) {
  const clip = state.clips.find((c) => c.name === name);
  if (!clip) throw new Error(`no clip named ${name}`);
  pause();
  state.mixer.stopAllAction();
  state.clip = clip;
  state.action = state.mixer.clipAction(clip);
  state.action.play();
  state.duration = clip.duration;
  setAudioSource(clip.name);
  setTime(0);
  fillClips();
  if (autoplay) play();
  refreshBar();
}

// ---------------------------------------------------------------- loop
// The panel and the bar cover part of the canvas: shift the projection so the view's centre is
// the centre of the free area.
function freeAreaOffset(w, h) {
  const panel = $('panel').getBoundingClientRect();
  const bar = $('bar').getBoundingClientRect();
  const left = panel.right < w / 2 ? panel.right : 0;
  const bottom = bar.top > h / 2 ? h - bar.top : 0;
  return { x: -left / 2, y: bottom / 2, width: w - left, height: Math.max(h - bottom, 1) };
}

let lastSize = '';
function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  const size = `${w}x${h}`;
  if (size === lastSize) return false;
  lastSize = size;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  const off = freeAreaOffset(w, h);
  camera.setViewOffset(w, h, off.x, off.y, w, h);
  camera.updateProjectionMatrix();
  return true;
}

const followAnchor = new THREE.Vector3();
// Keep a travelling figure in view: move camera and orbit target with its root, on the ground plane,
// and the key light (and its shadow box) with them.
function follow() {
  if (!$('follow').checked || !state.rootJoint) return;
  const now = state.rootJoint.object.getWorldPosition(tmp.a);
  const dx = now.x - followAnchor.x, dz = now.z - followAnchor.z;
  followAnchor.copy(now);
  for (const v of [camera.position, controls.target, key.position, key.target.position]) { v.x += dx; v.z += dz; }
}

const clock = new THREE.Timer();
// Frames are drawn only while something changes (playing, the camera moving, any input), so an
// idle page costs nothing.
function redraw() { dirty = true; }
const frameWaiters = [];
for (const type of ['input', 'change', 'pointermove', 'pointerdown', 'pointerup', 'wheel', 'keydown', 'resize']) {
  window.addEventListener(type, redraw, true);
}

function tick(timestamp) {
  clock.update(timestamp);
  const dt = Math.min(clock.getDelta(), 0.1);
  if (resize()) dirty = true;
  if (state.playing) { advance(dt); dirty = true; }
  if (controls.update()) dirty = true;
  if (dirty) {
    dirty = false;
    if (state.root) {
      updateOverlay();
      updateTargets();
      follow();
    }
    updateLabels();
    updateHover();
    renderer.render(scene, camera);
    refreshBar();
    api.frame++;
    for (const resolve of frameWaiters.splice(0)) resolve(api.frame);
  }
  requestAnimationFrame(tick);
}

// ---------------------------------------------------------------- scripting API
Object.assign(api, {
  play, pause,
  setTime: (t) => { setTime(t); refreshBar(); },
  selectClip: (name) => selectClip(name),
  selectEntry: (i) => selectEntry(i),
  // a promise of the next frame drawn: it shows everything done before the call
  nextFrame: () => new Promise((resolve) => { frameWaiters.push(resolve); dirty = true; }),
  frame: 0,
  state: () => ({
    entry: state.entryIndex, entries: DATA.entries.map((e) => e.name), file: state.info?.file,
    clips: state.clips.map((c) => c.name), clip: state.clip?.name ?? null, time: state.time, duration: state.duration,
    playing: state.playing, follow: $('follow').checked, mode: state.hasMesh ? 'mesh' : 'skeleton', joints: state.joints.length, bones: state.bones.length,
    lowConfidence: state.joints.filter((j) => j.low).map((j) => j.canonical.join(',')),
    targets: state.targets.map((t) => ({ name: t.name, kind: t.kind, position: t.position.toArray(), linked: !!t.line })),
    audio: { src: audio.dataset.src || null, currentTime: audio.currentTime, paused: audio.paused, blocked: audioBlocked },
    mapping: state.info?.mapping ?? null,
  }),
  jointsOnScreen: () => jointsOnScreen().map((s) => ({ name: s.joint.name, parent: state.joints[s.joint.parent]?.name ?? null,
    canonical: s.joint.canonical, low: s.joint.low, x: s.x, y: s.y, visible: s.visible })),
  tip: () => (tip.hidden ? null : tip.textContent),
});

function showError(err) {
  api.error = String((err && err.message) || err);
  const status = $('status');
  status.className = 'error';
  status.textContent = `Cannot show this file: ${api.error}`;
  console.error(err);
}

window.addEventListener('error', (e) => { api.error = String(e.message); });
requestAnimationFrame(tick);
selectEntry(DATA.start || 0).then(() => { api.ready = true; }).catch(showError);
