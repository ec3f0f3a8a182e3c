// motion-lod's web viewer: opens a .glb written by `motion-lod synth -o walk.glb` or
// `motion-lod crowd --export crowd.glb` (or any glTF 2.0 binary), plays its animation on a lit
// ground, colours crowd walkers by their level of detail frame by frame (from the node extras the
// exporter writes) and shows the legend. `motion-lod view FILE` serves it with FILE as model.glb.
//
// For tests, `window.viewer` tells whether a model is loaded and running, the animation time, and
// where the first character is on the screen.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const canvas = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
renderer.shadowMap.enabled = true;
renderer.shadowMap.type = THREE.PCFSoftShadowMap;

const BACKGROUND = new THREE.Color(0xdfe7ee);
const scene = new THREE.Scene();
scene.background = BACKGROUND;
scene.fog = new THREE.Fog(BACKGROUND, 60, 400);

const camera = new THREE.PerspectiveCamera(40, 1, 0.05, 2000);
camera.position.set(3.2, 1.8, 4.2);
const controls = new OrbitControls(camera, canvas);
controls.target.set(0, 0.9, 0);
controls.enableDamping = true;

scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8577, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 2.2);
sun.position.set(4, 9, 5);
sun.castShadow = true;
sun.shadow.mapSize.set(1024, 1024);
const sunBox = sun.shadow.camera;
sunBox.left = sunBox.bottom = -6;
sunBox.right = sunBox.top = 6;
sunBox.near = 0.5;
sunBox.far = 40;
sun.shadow.bias = -0.0005;
sun.shadow.normalBias = 0.02;
scene.add(sun, sun.target);

const ground = new THREE.Mesh(
  new THREE.PlaneGeometry(4000, 4000),
  new THREE.MeshStandardMaterial({ color: 0xbdbbb2, roughness: 1 }),
);
ground.rotation.x = -Math.PI / 2;
ground.receiveShadow = true;
scene.add(ground);
let grid = null;
function setGrid(size, cells) {
  if (grid) scene.remove(grid);
  grid = new THREE.GridHelper(size, cells, 0x6a6862, 0x8c8a82);
  grid.position.y = 0.002;
  scene.add(grid);
}
setGrid(200, 200);

const clock = new THREE.Clock();
let mixer = null;
let model = null;
let playing = true;
let follow = null; // the bone the camera follows (single walks)
const followLast = new THREE.Vector3();
let levelMeshes = []; // [{ mesh, levels }] for crowds
let levelMaterials = [];
let frameTime = 1 / 30;
let animTime = 0;
let duration = 0;
let ready = false;

const ui = {
  play: document.getElementById('play'),
  clock: document.getElementById('clock'),
  fileName: document.getElementById('file-name'),
  legend: document.getElementById('legend'),
  legendItems: document.getElementById('legend-items'),
  message: document.getElementById('message'),
};

function say(text) {
  ui.message.hidden = !text;
  ui.message.textContent = text || '';
}

function srgb([r, g, b]) {
  return new THREE.Color().setRGB(r / 255, g / 255, b / 255, THREE.SRGBColorSpace);
}

function clear() {
  if (model) scene.remove(model);
  model = null;
  mixer = null;
  follow = null;
  levelMeshes = [];
  levelMaterials = [];
  ready = false;
  animTime = 0;
  duration = 0;
}

function showLegend(info, counts) {
  ui.legendItems.replaceChildren();
  const legend = info?.legend ?? [];
  for (const [i, entry] of legend.entries()) {
    if (info.kind === 'crowd' && !counts[i]) continue;
    const li = document.createElement('li');
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    swatch.style.background = `rgb(${entry.color.join(',')})`;
    const label = document.createElement('span');
    label.textContent = entry.label;
    li.append(swatch, label);
    if (info.kind === 'crowd') {
      const count = document.createElement('span');
      count.className = 'count';
      count.textContent = `(${counts[i]})`;
      li.append(count);
    }
    ui.legendItems.append(li);
  }
  ui.legend.hidden = legend.length === 0;
}

function place(root, info) {
  if (follow) {
    // A single character: look at it from its front left, 5.4 m away, and follow it.
    follow.getWorldPosition(followLast);
    controls.target.set(followLast.x, 0.9, followLast.z);
    camera.position.set(followLast.x + 3.2, 1.7, followLast.z + 4.4);
  } else if (info?.camera) {
    // A crowd: behind and above the camera that chose the levels, looking the same way.
    const eye = new THREE.Vector3(...info.camera.position);
    const ahead = new THREE.Vector3(...info.camera.target).sub(eye).setY(0).normalize();
    controls.target.copy(eye).addScaledVector(ahead, 30).setY(0);
    camera.position.copy(eye).addScaledVector(ahead, -14).setY(12);
    camera.far = 4000;
    camera.updateProjectionMatrix();
  } else {
    // Anything else: frame the bones (or the meshes) of the whole scene.
    const box = new THREE.Box3();
    const p = new THREE.Vector3();
    root.traverse((o) => {
      if (o.isBone || o.isMesh) box.expandByPoint(o.getWorldPosition(p));
    });
    const size = box.getSize(new THREE.Vector3());
    const centre = box.getCenter(new THREE.Vector3());
    const span = Math.max(size.x, size.z, 1.8);
    controls.target.set(centre.x, 0.8, centre.z);
    camera.position.set(centre.x + 0.55 * span, 0.35 * span + 3, centre.z + 0.75 * span);
    camera.far = Math.max(2000, 4 * span);
    camera.updateProjectionMatrix();
  }
  controls.update();
}

async function load(url, name) {
  clear();
  say(`loading ${name} ...`);
  ui.fileName.textContent = name;
  let gltf;
  try {
    gltf = await new GLTFLoader().loadAsync(url);
  } catch (e) {
    say(`could not load ${name}: ${e.message ?? e}`);
    return;
  }
  say('');
  model = gltf.scene;
  const info = model.userData?.motion_lod ?? null;
  frameTime = info?.frame_time ?? 1 / 30;
  const skinned = [];
  model.traverse((o) => {
    if (o.isMesh) {
      o.castShadow = true;
      o.frustumCulled = false; // skinned bodies move far from their bind-pose bounds
      if (o.isSkinnedMesh) skinned.push(o);
    }
  });
  const counts = [];
  if (info?.kind === 'crowd') {
    levelMaterials = info.legend.map(
      (e) => new THREE.MeshStandardMaterial({ color: srgb(e.color), roughness: 0.75 }),
    );
    for (const mesh of skinned) {
      const levels = mesh.userData?.motion_lod?.levels;
      if (levels) levelMeshes.push({ mesh, levels });
    }
    for (const { levels } of levelMeshes) {
      const freq = new Map();
      for (const l of levels) freq.set(l, (freq.get(l) ?? 0) + 1);
      let best = 0;
      let bestCount = -1;
      for (const [l, c] of freq) if (c > bestCount || (c === bestCount && l < best)) [best, bestCount] = [l, c];
      counts[best] = (counts[best] ?? 0) + 1;
    }
  } else if (skinned.length > 0) {
    // Follow the node whose translation is animated (the motion root).
    const track = gltf.animations[0]?.tracks.find((t) => t.name.endsWith('.position'));
    const name = track ? track.name.slice(0, -'.position'.length) : null;
    follow = (name && model.getObjectByName(name)) || skinned[0].skeleton.bones[0];
  }
  if (info?.kind === 'crowd') setGrid(4 * Math.ceil(info.field_size_m ?? 200), Math.ceil(info.field_size_m ?? 200) / 5);
  else setGrid(200, 200);
  showLegend(info, counts);
  scene.add(model);
  if (gltf.animations.length > 0) {
    mixer = new THREE.AnimationMixer(model);
    for (const clip of gltf.animations) {
      mixer.clipAction(clip).play();
      duration = Math.max(duration, clip.duration);
    }
  }
  mixer?.update(0);
  model.updateMatrixWorld(true);
  place(model, info);
  clock.getDelta();
  ready = true;
}

function recolour() {
  if (levelMeshes.length === 0) return;
  const f = Math.floor(animTime / frameTime + 1e-6);
  for (const { mesh, levels } of levelMeshes) {
    const bin = levels[Math.min(f, levels.length - 1)];
    const m = levelMaterials[bin];
    if (m && mesh.material !== m) mesh.material = m;
  }
}

function resize() {
  const w = canvas.clientWidth;
  const h = canvas.clientHeight;
  if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) || canvas.height !== Math.floor(h * renderer.getPixelRatio())) {
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }
}

const followNow = new THREE.Vector3();
renderer.setAnimationLoop(() => {
  resize();
  const dt = Math.min(clock.getDelta(), 0.1);
  if (mixer && playing) {
    mixer.update(dt);
    animTime = duration > 0 ? mixer.time % duration : mixer.time;
  }
  recolour();
  if (follow) {
    follow.getWorldPosition(followNow);
    const dx = followNow.x - followLast.x;
    const dz = followNow.z - followLast.z;
    camera.position.x += dx;
    camera.position.z += dz;
    controls.target.x += dx;
    controls.target.z += dz;
    followLast.copy(followNow);
    sun.position.set(followNow.x + 4, 9, followNow.z + 5);
    sun.target.position.set(followNow.x, 0, followNow.z);
  }
  controls.update();
  ui.clock.textContent = `${animTime.toFixed(2)} s`;
  renderer.render(scene, camera);
});

ui.play.addEventListener('click', () => {
  playing = !playing;
  ui.play.textContent = playing ? 'pause' : 'play';
  clock.getDelta();
});
document.getElementById('open').addEventListener('change', (e) => {
  const file = e.target.files?.[0];
  if (file) load(URL.createObjectURL(file), file.name);
});
window.addEventListener('dragover', (e) => e.preventDefault());
window.addEventListener('drop', (e) => {
  e.preventDefault();
  const file = e.dataTransfer?.files?.[0];
  if (file) load(URL.createObjectURL(file), file.name);
});

// What tests read: whether a model runs, its animation time and the first character's screen box.
window.viewer = {
  get ready() {
    return ready;
  },
  time: () => animTime,
  kind: () => model?.userData?.motion_lod?.kind ?? null,
  characterScreenBox() {
    let mesh = null;
    model?.traverse((o) => {
      if (!mesh && o.isSkinnedMesh) mesh = o;
    });
    if (!mesh) return null;
    const rect = canvas.getBoundingClientRect();
    const box = { x0: Infinity, y0: Infinity, x1: -Infinity, y1: -Infinity };
    const p = new THREE.Vector3();
    for (const bone of mesh.skeleton.bones) {
      bone.getWorldPosition(p);
      p.project(camera);
      const x = rect.left + ((p.x + 1) / 2) * rect.width;
      const y = rect.top + ((1 - p.y) / 2) * rect.height;
      box.x0 = Math.min(box.x0, x);
      box.y0 = Math.min(box.y0, y);
      box.x1 = Math.max(box.x1, x);
      box.y1 = Math.max(box.y1, y);
    }
    return box;
  },
};

const params = new URLSearchParams(location.search);
const initial = params.get('file') ?? 'model.glb';
fetch(initial, { method: 'HEAD' })
  .then((r) => {
    // `motion-lod view` names the file it serves as model.glb in Content-Disposition.
    const served = /filename="([^"]+)"/.exec(r.headers.get('content-disposition') ?? '')?.[1];
    if (r.ok) load(initial, params.get('name') ?? served ?? decodeURIComponent(initial.split('/').pop()));
    else say('open a .glb (walk or crowd clip from motion-lod)');
  })
  .catch(() => say('open a .glb (walk or crowd clip from motion-lod)'));
