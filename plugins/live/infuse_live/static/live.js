// infuse serve's live page: the scene's characters, played from the server's pose stream, with speech.
// The server's WebSocket messages are described in infuse_live/protocol.py; scene units are metres, +Y up.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const $ = (id) => document.getElementById(id);
// Test and scripting hooks: frames applied, the last frame's number, and where a joint is (world metres).
const api = window.infuseLive = { ready: false, error: null, frames: 0, frame: -1, socket: null,
  jointPosition: (character, joint) => {
    const c = characters.get(character);
    const bone = c && c.bones[c.joints.indexOf(joint)];
    if (!bone) return null;
    bone.updateWorldMatrix(true, false);
    return bone.getWorldPosition(new THREE.Vector3()).toArray();
  } };

const canvas = $('view');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x1d2129);
const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 200);
camera.position.set(0, 1.6, 6);
const controls = new OrbitControls(camera, canvas);
controls.target.set(0, 1.0, 0);
scene.add(new THREE.HemisphereLight(0xe8efff, 0x4a4036, 1.8));
const sun = new THREE.DirectionalLight(0xffffff, 2.2);
sun.position.set(2, 5, 4);
scene.add(sun, new THREE.GridHelper(12, 24, 0x3a4150, 0x2a2f3a));

const characters = new Map(); // name -> {joints, bones: [Object3D|null], meshes, morphs}
let latest = null;            // the newest frame message not yet shown
const audio = { context: null, playing: new Map(), streamTime: 0 };

function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);

async function loadCharacter(name, info) {
  const gltf = await new GLTFLoader().loadAsync(info.model);
  const root = gltf.scene;
  const byName = new Map();
  root.traverse((o) => { if (!byName.has(o.name)) byName.set(o.name, o); });
  const bones = info.joints.map((j) => byName.get(THREE.PropertyBinding.sanitizeNodeName(j)) || byName.get(j) || null);
  const meshes = [];
  root.traverse((o) => { if (o.isMesh && o.morphTargetDictionary) meshes.push(o); });
  root.traverse((o) => { if (o.isMesh) o.frustumCulled = false; });
  scene.add(root);
  // The stream's root joint transform is in the world (metres, the placement included); the model's root
  // bone may hang under nodes that turn and scale it (an Armature at 0.01): undo them once, keep its scale.
  root.updateMatrixWorld(true);
  const top = bones[0];
  const above = top && top.parent ? top.parent.matrixWorld.clone().invert() : new THREE.Matrix4();
  const scale = top ? top.getWorldScale(new THREE.Vector3()) : new THREE.Vector3(1, 1, 1);
  // Streamed joint translations are metres; a bone's position is in its parent's units (an Armature at 0.01).
  const units = bones.map((b) => (b && b.parent ? 1 / b.parent.getWorldScale(new THREE.Vector3()).x : 1));
  characters.set(name, { joints: info.joints, morphs: info.morphs, bones, meshes, root, above, scale, units });
}

const placed = { m: new THREE.Matrix4(), p: new THREE.Vector3(), q: new THREE.Quaternion() };

// The first frame sets the view: across the line between the first two characters, all of them in sight.
function frameView(message) {
  const roots = Object.values(message.characters).map((c) => new THREE.Vector3(c.root[0], 0, c.root[2]));
  if (!roots.length) return;
  const centre = roots.reduce((a, b) => a.add(b), new THREE.Vector3()).divideScalar(roots.length);
  const across = roots.length > 1 ? new THREE.Vector3().subVectors(roots[1], roots[0]) : new THREE.Vector3(1, 0, 0);
  const spread = Math.max(across.length(), ...roots.map((r) => r.distanceTo(centre) * 2), 1.0);
  const side = new THREE.Vector3(-across.z, 0, across.x).normalize();
  if (side.lengthSq() === 0) side.set(0, 0, 1);
  controls.target.set(centre.x, 1.0, centre.z);
  camera.position.copy(centre).addScaledVector(side, 2.2 * spread + 2.0).setY(1.5);
  controls.update();
}

function applyFrame(message) {
  for (const [name, pose] of Object.entries(message.characters)) {
    const c = characters.get(name);
    if (!c) continue;
    const r = pose.rotations;
    c.bones.forEach((bone, j) => { if (bone && j > 0) bone.quaternion.set(r[4 * j], r[4 * j + 1], r[4 * j + 2], r[4 * j + 3]); });
    const t = pose.translations; // only for characters whose joints are placed by translation (carried feet)
    if (t) c.bones.forEach((bone, j) => { if (bone && j > 0) bone.position.set(t[3 * j], t[3 * j + 1], t[3 * j + 2]).multiplyScalar(c.units[j]); });
    const top = c.bones[0];
    if (top) {
      placed.p.set(pose.root[0], pose.root[1], pose.root[2]);
      placed.q.set(r[0], r[1], r[2], r[3]);
      placed.m.compose(placed.p, placed.q, c.scale).premultiply(c.above);
      placed.m.decompose(top.position, top.quaternion, top.scale);
    }
    for (const mesh of c.meshes) {
      pose.morphs.forEach((w, k) => {
        const index = mesh.morphTargetDictionary[c.morphs[k]];
        if (index !== undefined) mesh.morphTargetInfluences[index] = w;
      });
    }
  }
  if (api.frames === 0) frameView(message);
  audio.streamTime = message.time;
  api.frame = message.frame;
  api.frames += 1;
}

// Speech: each utterance's WAV arrives when it starts; it plays from where the stream is in it.
async function playAudio(message) {
  if (!audio.context) audio.context = new AudioContext();
  const key = `${message.character}/${message.block}`;
  if (message.stop !== undefined) {
    const playing = audio.playing.get(key);
    if (playing) {
      playing.gain.gain.setTargetAtTime(0, audio.context.currentTime, 0.02); // a short fade, as in the WAV
      playing.source.stop(audio.context.currentTime + 0.1);
      audio.playing.delete(key);
    }
    return;
  }
  const bytes = Uint8Array.from(atob(message.wav), (ch) => ch.charCodeAt(0));
  const buffer = await audio.context.decodeAudioData(bytes.buffer);
  const source = audio.context.createBufferSource();
  const gain = audio.context.createGain();
  source.buffer = buffer;
  source.connect(gain).connect(audio.context.destination);
  source.start(0, Math.max(0, audio.streamTime - message.start));
  audio.playing.set(key, { source, gain });
  source.onended = () => { if (audio.playing.get(key)?.source === source) audio.playing.delete(key); };
  if (audio.context.state === 'suspended') $('audio').hidden = false;
}
$('audio').addEventListener('click', () => { audio.context?.resume(); $('audio').hidden = true; });

// A binary frame: uint32 header length, JSON header {frame, time, characters: [[name, J, M]...]}, then
// float32 rotations (J*4), root (3) and morphs (M) per character, and translations (J*3) after the morphs
// of a character listed as [name, J, M, true] (see infuse_live/frames.py binary_frame).
function decodeFrame(buffer) {
  const length = new DataView(buffer).getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, length)));
  const values = new Float32Array(buffer.slice(4 + length));
  const characters = {};
  let at = 0;
  for (const [name, joints, morphs, translated] of header.characters) {
    characters[name] = { rotations: values.subarray(at, at + 4 * joints),
      root: values.subarray(at + 4 * joints, at + 4 * joints + 3),
      morphs: values.subarray(at + 4 * joints + 3, at + 4 * joints + 3 + morphs) };
    at += 4 * joints + 3 + morphs;
    if (translated) {
      characters[name].translations = values.subarray(at, at + 3 * joints);
      at += 3 * joints;
    }
  }
  return { type: 'frame', frame: header.frame, time: header.time, characters };
}

async function connect() {
  const config = await (await fetch('/live.json' + location.search)).json();
  const token = new URLSearchParams(location.search).get('token');
  const url = `ws://${location.hostname}:${config.websocket_port}/` + (token ? `?token=${encodeURIComponent(token)}` : '');
  const socket = api.socket = new WebSocket(url);
  socket.binaryType = 'arraybuffer';
  let loading = Promise.resolve();
  socket.onmessage = (event) => {
    if (event.data instanceof ArrayBuffer) { latest = decodeFrame(event.data); return; }
    const message = JSON.parse(event.data);
    if (message.type === 'hello') {
      loading = Promise.all(Object.entries(message.characters).map(([name, info]) =>
        loadCharacter(name, { ...info, model: info.model + location.search }))).then(() => {
        socket.send(JSON.stringify({ type: 'subscribe', frames: true, feedback: 'none', format: 'binary' }));
        $('status').textContent = `${characters.size} characters at ${message.fps} fps`;
        api.ready = true;
      }).catch((error) => { api.error = String(error); $('status').textContent = `Error: ${error}`; });
    } else if (message.type === 'character') {  // one that joined the running scene
      loading = loading.then(() => loadCharacter(message.name, { ...message, model: message.model + location.search }))
        .then(() => { $('status').textContent = `${characters.size} characters`; })
        .catch((error) => { api.error = String(error); });
    } else if (message.type === 'frame') {
      latest = message;
    } else if (message.type === 'audio') {
      loading.then(() => playAudio(message)).catch((error) => { api.error = String(error); });
    } else if (message.type === 'error') {
      $('status').textContent = `Error: ${message.message}`;
    }
  };
  socket.onclose = () => { $('status').textContent = 'Disconnected'; };
}

function tick() {
  requestAnimationFrame(tick);
  if (latest) { applyFrame(latest); latest = null; }
  controls.update();
  renderer.render(scene, camera);
}
resize();
tick();
connect().catch((error) => { api.error = String(error); $('status').textContent = `Error: ${error}`; });
