// motion-lod live: the runtime compiled to WebAssembly (mlod.js) synthesizes walks in the page.
// One walker steered from sliders and the keyboard (its controls apply at its next cycle, as the
// runtime chains cycles, with the foot lock), or a crowd whose level of detail the runtime's
// policy chooses every frame from this page's camera. The page only draws: bones as camera-facing
// ribbons coloured by level, a walker the policy leaves root only as a single grey body (in a
// crowd a point sprite), on a ground that is cleared rather than drawn (software GL pays for
// every pixel, line and primitive: see `clearGroundAndSky`, `Bodies`).
//
// `motion-lod view MODEL.mlod` serves this page with the model as model.mlod; a model file can
// also be picked or dropped. For tests, `window.live` runs the scripted walk and crowd of
// crowd.js, steers the walker, and reports timings.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { Runtime, Model, Walker, TRANSFORM_FLOATS, STATE_BYTES } from './mlod.js';
import { Crowd, runWalk, runCrowd, benchPose, benchStep } from './crowd.js';

const canvas = document.getElementById('view');
// `?fast` draws without antialiasing at one pixel per CSS pixel (software GL, timing runs).
// `?sync` waits for the GPU after each frame, so the drawing time includes its raster.
const fast = new URLSearchParams(location.search).has('fast');
const sync = new URLSearchParams(location.search).has('sync');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: !fast, preserveDrawingBuffer: !fast });
renderer.setPixelRatio(fast ? 1 : Math.min(window.devicePixelRatio, 2));

const BACKGROUND = new THREE.Color(0xdfe7ee);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, 1, 0.05, 3000);
camera.position.set(3.2, 1.8, 4.2);
const orbit = new OrbitControls(camera, canvas);
orbit.target.set(0, 0.9, 0);
orbit.enableDamping = true;
// The ground is not drawn but cleared: an endless plane at y = 0 out to the camera's far distance,
// in the colour a Lambert plane of albedo 0xbdbbb2 under the sky light (white, 1.6) has, and the
// background above its horizon. Two scissored clears cost next to nothing on software GL, where
// shading the plane over most of the picture cost the GPU process about 10 ms of CPU a frame.
const SKY_LIGHT = 1.6;
const GROUND = new THREE.Color(0xbdbbb2).multiplyScalar(SKY_LIGHT / Math.PI);
scene.background = null;
renderer.autoClear = false;
const groundView = { dir: new THREE.Vector3(), size: new THREE.Vector2() };
function clearGroundAndSky() {
  const { width, height } = renderer.getSize(groundView.size);
  // The camera never rolls (OrbitControls keeps y up), so the ground's far edge is a row: a
  // point of the ground at the far distance ahead, f along the view, lies at NDC y
  // (f sin(pitch) - camera y) / (f cos(pitch) tan(fov / 2)); the ground is below it.
  const dir = camera.getWorldDirection(groundView.dir);
  const down = -dir.y;
  const level = Math.hypot(dir.x, dir.z);
  const f = camera.far;
  const y = camera.position.y;
  let rows = 0;
  if (y > 0) {
    const ndc = level > 1e-6 ? (f * down - y) / (f * level * Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2)) : 1;
    rows = Math.min(height, Math.max(0, Math.round(0.5 * (ndc + 1) * height)));
  }
  renderer.setScissorTest(true);
  if (rows > 0) {
    renderer.setScissor(0, 0, width, rows);
    renderer.setClearColor(GROUND);
    renderer.clear(true, true, false);
  }
  if (rows < height) {
    renderer.setScissor(0, rows, width, height - rows);
    renderer.setClearColor(BACKGROUND);
    renderer.clear(true, true, false);
  }
  renderer.setScissorTest(false);
}

/// Draws the frame: the ground and sky, then the scene.
function draw() {
  clearGroundAndSky();
  renderer.render(scene, camera);
}
let grid = null;
function setGrid(size, cells) {
  if (grid) scene.remove(grid);
  grid = new THREE.GridHelper(size, cells, 0x4f4d48, 0x6c6a64);
  grid.position.y = 0.002;
  scene.add(grid);
}
setGrid(200, 200);

// Colours by accuracy level (0 the most accurate), as the glTF crowd export's legend.
const PALETTE = [[220, 30, 30], [235, 120, 20], [225, 190, 30], [60, 170, 60], [30, 160, 170],
  [40, 90, 210], [120, 60, 200], [190, 60, 160]].map(([r, g, b]) => new THREE.Color().setRGB(r / 255, g / 255, b / 255, THREE.SRGBColorSpace));
const ROOT_ONLY = new THREE.Color().setRGB(0.45, 0.47, 0.52, THREE.SRGBColorSpace);
const colourOf = (level) => PALETTE[level % PALETTE.length];

/// Segments drawn as camera-facing ribbons shaded as round tubes, all in one draw call: four
/// vertices a segment, each with the segment's start, end, colour and radius (10 floats), spread
/// sideways by the vertex shader. (Instancing one mesh per bone is slower on software GL, which
/// pays per instance.)
class Segments {
  constructor() {
    this.geometry = new THREE.BufferGeometry();
    const material = new THREE.ShaderMaterial({
      vertexShader: `
        attribute vec3 aStart; attribute vec3 aEnd; attribute vec3 aColor; attribute float aRadius;
        attribute vec2 aCorner;
        varying vec3 vColor; varying float vSide;
        void main() {
          vec3 p = mix(aStart, aEnd, aCorner.y);
          vec3 axis = aEnd - aStart;
          vec3 side = cross(axis, cameraPosition - p);
          float len = length(side);
          side = len > 1e-9 ? side / len : vec3(1.0, 0.0, 0.0);
          p += side * (aRadius * aCorner.x);
          vColor = aColor;
          vSide = aCorner.x;
          gl_Position = projectionMatrix * viewMatrix * vec4(p, 1.0);
        }`,
      fragmentShader: `
        varying vec3 vColor; varying float vSide;
        void main() {
          float light = 0.55 + 0.45 * sqrt(max(1.0 - vSide * vSide, 0.0)) - 0.15 * vSide;
          gl_FragColor = vec4(vColor * light, 1.0);
          #include <colorspace_fragment>
        }`,
      side: THREE.DoubleSide,
    });
    this.mesh = new THREE.Mesh(this.geometry, material);
    this.mesh.frustumCulled = false;
    this.capacity = 0;
    this.count = 0;
    this.grow(8192);
  }

  grow(capacity) {
    const data = new Float32Array(capacity * 40);
    if (this.data) data.set(this.data.subarray(0, this.count * 40));
    this.data = data;
    this.buffer = new THREE.InterleavedBuffer(data, 10).setUsage(THREE.DynamicDrawUsage);
    const corner = new Float32Array(capacity * 8);
    const index = new Uint32Array(capacity * 6);
    for (let k = 0; k < capacity; k++) {
      corner.set([-1, 0, 1, 0, 1, 1, -1, 1], 8 * k);
      const v = 4 * k;
      index.set([v, v + 1, v + 2, v, v + 2, v + 3], 6 * k);
    }
    const g = this.geometry;
    g.setIndex(new THREE.BufferAttribute(index, 1));
    g.setAttribute('aStart', new THREE.InterleavedBufferAttribute(this.buffer, 3, 0));
    g.setAttribute('aEnd', new THREE.InterleavedBufferAttribute(this.buffer, 3, 3));
    g.setAttribute('aColor', new THREE.InterleavedBufferAttribute(this.buffer, 3, 6));
    g.setAttribute('aRadius', new THREE.InterleavedBufferAttribute(this.buffer, 1, 9));
    g.setAttribute('aCorner', new THREE.BufferAttribute(corner, 2));
    // three.js needs a position attribute to count vertices; the shader does not read it.
    g.setAttribute('position', new THREE.InterleavedBufferAttribute(this.buffer, 3, 0));
    this.capacity = capacity;
  }

  begin() { this.count = 0; }

  reserve(n) {
    if (this.count + n > this.capacity) this.grow(Math.max(2 * this.capacity, this.count + n));
  }

  push(sx, sy, sz, ex, ey, ez, c, radius) {
    if (this.count === this.capacity) this.grow(2 * this.capacity);
    const d = this.data;
    let i = this.count++ * 40;
    for (let v = 0; v < 4; v++, i += 10) {
      d[i] = sx; d[i + 1] = sy; d[i + 2] = sz; d[i + 3] = ex; d[i + 4] = ey; d[i + 5] = ez;
      d[i + 6] = c.r; d[i + 7] = c.g; d[i + 8] = c.b; d[i + 9] = radius;
    }
  }

  end() {
    this.buffer.clearUpdateRanges();
    this.buffer.addUpdateRange(0, this.count * 40);
    this.buffer.needsUpdate = true;
    this.geometry.setDrawRange(0, this.count * 6);
  }
}

const segments = new Segments();
scene.add(segments.mesh);

/// Root-only walkers of a crowd drawn as points, one vertex a walker (its root x, the top of its
/// body, z: 3 floats), each a round grey body cut out of its point sprite by the fragment shader,
/// sized by its distance; the same body the ribbon of `Segments` draws (from 0.08 m to 0.65 m above
/// the root, radius 0.18 m), seen from the side. On software GL a point is one primitive of one
/// vertex where a ribbon is two triangles of four vertices of 40 bytes: most of a large crowd is
/// root only (about 6,900 of 10,000 walkers in view from the page's crowd camera).
class Bodies {
  constructor() {
    this.geometry = new THREE.BufferGeometry();
    this.material = new THREE.ShaderMaterial({
      uniforms: { uColor: { value: ROOT_ONLY }, uPixels: { value: 1 } },
      vertexShader: `
        uniform float uPixels;
        varying float vHalf;
        void main() {
          float bottom = 0.08;
          float h = position.y - bottom;
          vec4 clip = projectionMatrix * viewMatrix * vec4(position.x, bottom + 0.5 * h, position.z, 1.0);
          float size = max(h * uPixels / max(clip.w, 1e-6), 1.0);
          gl_PointSize = size;
          // The body's half width across the sprite, at least a pixel's.
          vHalf = max(0.18 / h, 0.6 / size);
          gl_Position = clip;
        }`,
      fragmentShader: `
        uniform vec3 uColor;
        varying float vHalf;
        void main() {
          float side = (gl_PointCoord.x - 0.5) / vHalf;
          if (abs(side) > 1.0) discard;
          float light = 0.55 + 0.45 * sqrt(max(1.0 - side * side, 0.0)) - 0.15 * side;
          gl_FragColor = vec4(uColor * light, 1.0);
          #include <colorspace_fragment>
        }`,
    });
    this.points = new THREE.Points(this.geometry, this.material);
    this.points.frustumCulled = false;
    this.count = 0;
    this.grow(4096);
  }

  grow(capacity) {
    const data = new Float32Array(capacity * 3);
    if (this.data) data.set(this.data.subarray(0, this.count * 3));
    this.data = data;
    this.attribute = new THREE.BufferAttribute(data, 3).setUsage(THREE.DynamicDrawUsage);
    this.geometry.setAttribute('position', this.attribute);
    this.capacity = capacity;
  }

  begin() { this.count = 0; }

  /// A body whose root is at (x, y, z).
  push(x, y, z) {
    if (this.count === this.capacity) this.grow(2 * this.capacity);
    const d = this.data;
    const i = this.count++ * 3;
    d[i] = x; d[i + 1] = y + 0.65; d[i + 2] = z;
  }

  /// Uploads the used range; `uPixels` turns a height over the clip w into pixels.
  end(camera, renderer) {
    this.attribute.clearUpdateRanges();
    this.attribute.addUpdateRange(0, this.count * 3);
    this.attribute.needsUpdate = true;
    this.geometry.setDrawRange(0, this.count);
    this.material.uniforms.uPixels.value = 0.5 * camera.projectionMatrix.elements[5] * renderer.getDrawingBufferSize(bodiesSize).y;
  }
}
const bodiesSize = new THREE.Vector2();

const bodies = new Bodies();
scene.add(bodies.points);

const ui = Object.fromEntries(['version', 'file-name', 'walk-panel', 'crowd-panel', 'dz', 'turn',
  'dx', 'height', 'style', 'style-row', 'detail', 'foot-lock', 'walk-readout', 'count', 'timing',
  'legend', 'legend-items', 'message', 'open', 'record'].map((id) => [id.replace(/-(\w)/g, (_, c) => c.toUpperCase()), document.getElementById(id)]));

function say(text) {
  ui.message.hidden = !text;
  ui.message.textContent = text || '';
}

let runtime = null;
let model = null;
let mode = 'walk';
let walker = null;
let crowd = null;
let cameraPtr = 0;
let ready = false;
let followLast = null;
const followStep = new THREE.Vector3();
// A message the readout shows for a while (a key for a control the model ignores).
let notice = { text: '', until: 0 };
// A walk being recorded (frames as `motion-lod quality --recorded` reads them), or null.
let recording = null;
/// The fixed step of a recorded walk, seconds: the page steps the walker by it every frame while
/// recording, whatever the frame rate, so the file has a steady frame time.
const RECORD_STEP_S = 1 / 60;
const timing = { frames: 0, runtime: 0, fk: 0, draw: 0, frame: 0, last: 0 };
const levelCounts = [];

/// The page's camera as the runtime's policy sees it.
const cameraDirection = new THREE.Vector3();
function writeCamera() {
  const dir = camera.getWorldDirection(cameraDirection);
  runtime.writeCamera(cameraPtr, {
    position: camera.position.toArray(), direction: dir.toArray(),
    fovY: THREE.MathUtils.degToRad(camera.fov), aspect: camera.aspect,
    heightPx: Math.max(1, canvas.height), near: camera.near, far: camera.far,
  });
}

const lerp = (a, b, t) => a + (b - a) * t;
function slider(name) { return Number(ui[name].value); }

/// The walker's controls from the panel: each slider spans the model's range of that control.
function panelControls() {
  const { min, max } = model;
  const style = new Array(8).fill(0);
  const s = ui.style.value;
  if (s !== 'data') for (const [k, w] of s.split(',').map((p) => p.split('='))) style[Number(k)] = Number(w);
  return { dx: lerp(min.dx, max.dx, slider('dx')), dz: lerp(min.dz, max.dz, slider('dz')),
    turn: lerp(min.turn, max.turn, slider('turn')), height: lerp(min.height, max.height, slider('height')), style };
}

function showControls() {
  const c = panelControls();
  // A control the model ignores is shown as such, its slider off.
  for (const name of ['dz', 'turn', 'dx', 'height']) {
    const off = model.ignored.has(name);
    ui[name].disabled = off;
    ui[name].title = off ? `this model ignores ${name}: the build found no signal in it (motion-lod info says why); the walk follows what the data imply` : '';
  }
  document.getElementById('dz-out').textContent = `${c.dz.toFixed(2)} m`;
  document.getElementById('dx-out').textContent = `${c.dx.toFixed(2)} m`;
  document.getElementById('turn-out').textContent = `${THREE.MathUtils.radToDeg(c.turn).toFixed(0)} deg`;
  document.getElementById('height-out').textContent = `${c.height.toFixed(2)} m`;
  for (const name of model.ignored) document.getElementById(`${name}-out`).textContent = 'ignored';
}

function fillPanel() {
  ui.style.replaceChildren();
  const add = (value, text) => { const o = document.createElement('option'); o.value = value; o.textContent = text; ui.style.append(o); };
  add('data', 'the data\'s mix');
  model.styles.forEach((s, k) => add(`${k}=1`, s.name));
  for (let a = 0; a < model.styles.length; a++) {
    for (let b = a + 1; b < model.styles.length; b++) add(`${a}=0.5,${b}=0.5`, `${model.styles[a].name} + ${model.styles[b].name}`);
  }
  ui.styleRow.hidden = model.styles.length === 0;
  ui.detail.replaceChildren();
  const addDetail = (value, text) => { const o = document.createElement('option'); o.value = value; o.textContent = text; ui.detail.append(o); };
  addDetail('auto', 'from the camera');
  for (let l = 0; l < model.levels; l++) addDetail(`${l}`, `level ${l}`);
  addDetail('root', 'root only');
  showControls();
}

/// The detail the panel asks for, or null for the camera's.
function panelDetail() {
  const v = ui.detail.value;
  if (v === 'auto') return null;
  if (v === 'root') return { level: model.levels - 1, joints: 0 };
  return { level: Number(v), joints: model.animatedJoints };
}

function clearWalkers() {
  walker?.free();
  walker = null;
  crowd?.free();
  crowd = null;
  segments.begin();
  segments.end();
  bodies.begin();
  bodies.end(camera, renderer);
}

function startWalk() {
  clearWalkers();
  walker = new Walker(model);
  walker.setFootLock(ui.footLock.checked);
  walker.start(panelControls(), panelDetail() ?? { level: 0, joints: model.animatedJoints }, 0, 0, 0);
  // From the walker's front right, the walker right of the screen's centre (clear of the panel).
  camera.position.set(3.2, 1.8, 4.2);
  orbit.target.set(-0.8, 0.9, 0.6);
  followLast = new THREE.Vector3(0, 0, 0);
  setGrid(200, 200);
}

/// Crowd presets: eight control sets spread over the model's range (speeds, gentle turns both
/// ways, sidesteps, heights), each walker's styles drawn from the model's.
function crowdPresets() {
  const { min, max } = model;
  const styles = model.styles.length;
  return Array.from({ length: 8 }, (_, p) => {
    const style = new Array(8).fill(0);
    if (styles > 0) style[p % styles] = 1;
    return {
      dx: lerp(min.dx, max.dx, [0.5, 0.4, 0.6, 0.5][p % 4]), dz: lerp(min.dz, max.dz, 0.15 + 0.7 * p / 7),
      turn: lerp(min.turn, max.turn, [0.5, 0.3, 0.7, 0.5, 0.42, 0.58, 0.5, 0.5][p]),
      height: lerp(min.height, max.height, [0.3, 0.7][p % 2]), style,
    };
  });
}

function startCrowd(n) {
  clearWalkers();
  // On a disc of 0.01 walkers per square metre (the paper's density) around the origin.
  const radius = Math.sqrt(n / 0.01 / Math.PI);
  const starts = Array.from({ length: n }, (_, i) => {
    const r = radius * Math.sqrt((i + 0.5) / n);
    const a = i * 2.399963; // the golden angle
    return [r * Math.sin(a), r * Math.cos(a), (i * 0.7) % (2 * Math.PI) - Math.PI];
  });
  crowd = new Crowd(model, { starts, presets: crowdPresets() });
  camera.position.set(0, 14, -radius - 20);
  orbit.target.set(0, 0, -radius + 40);
  orbit.update();
  // Cells of 10 m, doubled until at most 64 a side: each line spans the picture, and software GL
  // pays for every one (about 3 ms of the GPU process's CPU a frame for 124 lines at 10,000).
  let cell = 10;
  while (2.2 * radius / cell > 64) cell *= 2;
  setGrid(Math.ceil(2.2 * radius / cell) * cell, Math.ceil(2.2 * radius / cell));
  writeCamera();
  crowd.start(cameraPtr);
  followLast = null;
}

// A walker state's words (MlodWalkerState, mlod.js): level, joints (u32), and in doubles (index of
// the state's first double plus): root position, the cycle frame's origin x, z and heading.
const STATE_WORDS = STATE_BYTES >> 2;
const STATE_LEVEL = 92 >> 2;
const STATE_JOINTS = 96 >> 2;
const STATE_ROOT_F64 = 24 >> 3;
const STATE_FRAME_F64 = 48 >> 3;

/// Adds a walker's bones (its joints in the world) or, root only, a single body (a crowd draws
/// its root-only walkers as points of `bodies` instead).
function drawWalker(w, colour) {
  const f = runtime.f32;
  const d = runtime.f64;
  const s = w.state >> 3;
  const joints = w.joints();
  if (joints === 0) {
    const r = s + STATE_ROOT_F64;
    const x = d[r], y = d[r + 1], z = d[r + 2];
    segments.push(x, 0.08, z, x, y + 0.65, z, ROOT_ONLY, 0.18);
    return;
  }
  const o = s + STATE_FRAME_F64;
  const cx = d[o], cz = d[o + 1], h = d[o + 2];
  const c = Math.cos(h), sn = Math.sin(h);
  const at = w.transforms >> 2;
  const parents = model.parents;
  const J = model.joints;
  segments.reserve(J);
  for (let j = 0; j < J; j++) {
    const p = parents[j];
    if (p < 0) continue;
    const a = at + TRANSFORM_FLOATS * p + 4, b = at + TRANSFORM_FLOATS * j + 4;
    segments.push(c * f[a] + sn * f[a + 2] + cx, f[a + 1], -sn * f[a] + c * f[a + 2] + cz,
      c * f[b] + sn * f[b + 2] + cx, f[b + 1], -sn * f[b] + c * f[b + 2] + cz, colour, 0.035);
  }
}

function frame(now) {
  const dt = recording ? RECORD_STEP_S : Math.min(Math.max((now - (timing.last || now)) / 1000, 1 / 240), 0.1);
  timing.frame += timing.last ? now - timing.last : 0;
  timing.last = now;
  const w = canvas.clientWidth, hgt = canvas.clientHeight;
  if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) || canvas.height !== Math.floor(hgt * renderer.getPixelRatio())) {
    renderer.setSize(w, hgt, false);
    camera.aspect = w / hgt;
    camera.updateProjectionMatrix();
  }
  orbit.update();
  if (!ready) {
    draw();
    return;
  }
  writeCamera();
  const t0 = performance.now();
  levelCounts.length = 0;
  segments.begin();
  bodies.begin();
  let t1, t2;
  if (walker) {
    const fixed = panelDetail();
    if (fixed) walker.setDetail(fixed);
    else walker.detailFromCamera(cameraPtr, 1.2);
    walker.advance(dt, panelControls());
    t1 = performance.now();
    if (recording) record();
    walker.computeTransforms();
    t2 = performance.now();
    drawWalker(walker, colourOf(walker.level()));
    levelCounts[walker.joints() ? walker.level() : model.levels] = 1;
    // Follow the walker: the camera and its target move with the root.
    followStep.set(walker.rootX() - followLast.x, 0, walker.rootZ() - followLast.z);
    camera.position.add(followStep);
    orbit.target.add(followStep);
    followLast.add(followStep);
    const s = walker.readState();
    ui.walkReadout.textContent = (performance.now() < notice.until ? `${notice.text}; ` : '') + `cycle ${s.cycle}, ${(slider('dz') >= 0 ? panelControls().dz / s.cycleDuration : 0).toFixed(2)} m/s, ` +
      `level ${s.level} with ${s.joints} joints${s.footLocked ? ', feet locked' : ''}`;
  } else if (crowd) {
    crowd.step(dt, cameraPtr);
    t1 = performance.now();
    // Every walker's state read in place, from the crowd's array of states (no call a walker).
    const { walkers } = crowd;
    const n = walkers.length;
    const { bytes, u32 } = runtime.views();
    const visible = crowd.visiblePtr;
    const states = crowd.states >> 2;
    for (let i = 0, s = states; i < n; i++, s += STATE_WORDS) {
      if (bytes[visible + i] && u32[s + STATE_JOINTS] > 0) walkers[i].computeTransforms();
    }
    t2 = performance.now();
    const d = runtime.f64;
    let rootOnly = 0;
    for (let i = 0, s = states; i < n; i++, s += STATE_WORDS) {
      if (!bytes[visible + i]) continue;
      if (u32[s + STATE_JOINTS] === 0) {
        // The state's doubles start at word s (states are 8-byte aligned).
        const r = (s >> 1) + STATE_ROOT_F64;
        bodies.push(d[r], d[r + 1], d[r + 2]);
        rootOnly++;
        continue;
      }
      const level = u32[s + STATE_LEVEL];
      levelCounts[level] = (levelCounts[level] ?? 0) + 1;
      drawWalker(walkers[i], colourOf(level));
    }
    if (rootOnly) levelCounts[model.levels] = rootOnly;
  }
  segments.end();
  bodies.end(camera, renderer);
  draw();
  if (sync) renderer.getContext().finish();
  const t3 = performance.now();
  timing.frames++;
  timing.runtime += t1 - t0;
  timing.fk += t2 - t1;
  timing.draw += t3 - t2;
  if (timing.frames % 30 === 0) showTiming();
}

function showTiming() {
  const n = timing.frames || 1;
  const walkers = walker ? 1 : crowd?.count ?? 0;
  ui.timing.textContent = `${walkers} walker${walkers === 1 ? '' : 's'}: ${(timing.frame / Math.max(1, n - 1)).toFixed(1)} ms a frame\n` +
    `runtime: clips and poses ${(timing.runtime / n).toFixed(2)} ms, FK ${(timing.fk / n).toFixed(2)} ms\n` +
    `drawing: ${(timing.draw / n).toFixed(2)} ms`;
  ui.legendItems.replaceChildren();
  levelCounts.forEach((count, level) => {
    if (!count) return;
    const li = document.createElement('li');
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    swatch.style.background = `#${(level === model.levels ? ROOT_ONLY : colourOf(level)).getHexString()}`;
    const label = document.createElement('span');
    label.textContent = level === model.levels ? 'root only' : `level ${level}`;
    const c = document.createElement('span');
    c.className = 'count';
    c.textContent = `(${count})`;
    li.append(swatch, label, c);
    ui.legendItems.append(li);
  });
  ui.legend.hidden = levelCounts.length === 0;
}

function resetTiming() {
  Object.assign(timing, { frames: 0, runtime: 0, fk: 0, draw: 0, frame: 0, last: 0 });
}

function setMode(m, count) {
  mode = m;
  ui.walkPanel.hidden = m !== 'walk';
  ui.crowdPanel.hidden = m !== 'crowd';
  document.querySelector(`input[name=mode][value=${m}]`).checked = true;
  if (count) ui.count.value = String(count);
  if (m === 'walk') startWalk();
  else startCrowd(Number(ui.count.value));
  resetTiming();
}

async function openModel(bytes, name) {
  ready = false;
  clearWalkers();
  model?.free();
  model = null;
  try {
    model = new Model(runtime, bytes);
  } catch (e) {
    say(`could not open ${name}: ${e.message}`);
    return;
  }
  ui.fileName.textContent = `${name}: ${model.joints} joints, ${model.levels} levels` +
    (model.styles.length ? `, styles ${model.styles.map((s) => s.name).join(', ')}` : '');
  fillPanel();
  say('');
  setMode(mode);
  ready = true;
}

/// Adds the walker's frame to the recording.
function record() {
  const s = walker.readState();
  recording.frames.push({ cycle: s.cycle, cycleX: s.cycleX, cycleZ: s.cycleZ, heading: s.heading,
    level: s.level, joints: s.joints, bodyScale: s.bodyScale, pose: Array.from(walker.shownPose()) });
}

/// Starts recording the walker (fixed steps of RECORD_STEP_S).
function startRecording() {
  if (!walker) setMode('walk');
  recording = { format: 'motion-lod recorded walk', version: 1, frameTime: RECORD_STEP_S,
    poseLen: model.poseLen, joints: model.joints, frames: [] };
  ui.record.textContent = 'stop and save';
}

/// Stops recording and returns the recording (frames of the walker as shown: its cycle, the cycle
/// frame, its detail and body scale, and the pose vector in the cycle frame).
function stopRecording() {
  const r = recording;
  recording = null;
  ui.record.textContent = 'record';
  return r;
}

ui.record.addEventListener('click', () => {
  if (!recording) {
    startRecording();
    return;
  }
  const r = stopRecording();
  const url = URL.createObjectURL(new Blob([JSON.stringify(r)], { type: 'application/json' }));
  const a = document.createElement('a');
  a.href = url;
  a.download = 'walk-recording.json';
  a.click();
  URL.revokeObjectURL(url);
});

// Steering: keys move the sliders; the walker takes the new controls at its next cycle.
const KEYS = { KeyW: ['dz', 1], ArrowUp: ['dz', 1], KeyS: ['dz', -1], ArrowDown: ['dz', -1],
  KeyA: ['turn', -1], ArrowLeft: ['turn', -1], KeyD: ['turn', 1], ArrowRight: ['turn', 1],
  KeyQ: ['dx', -1], KeyE: ['dx', 1] };
window.addEventListener('keydown', (e) => {
  const k = KEYS[e.code];
  if (!k || mode !== 'walk') return;
  const [name, sign] = k;
  if (model.ignored.has(name)) {
    notice = { text: `this model ignores ${name} (no signal in its data)`, until: performance.now() + 2500 };
    ui.walkReadout.textContent = notice.text;
    e.preventDefault();
    return;
  }
  ui[name].value = String(Math.min(1, Math.max(0, slider(name) + 0.05 * sign)));
  showControls();
  e.preventDefault();
});
for (const id of ['dz', 'turn', 'dx', 'height', 'style']) ui[id].addEventListener('input', showControls);
ui.footLock.addEventListener('change', () => walker?.setFootLock(ui.footLock.checked));
ui.count.addEventListener('change', () => setMode('crowd'));
for (const r of document.querySelectorAll('input[name=mode]')) r.addEventListener('change', () => setMode(r.value));
ui.open.addEventListener('change', async (e) => {
  const file = e.target.files?.[0];
  if (file) openModel(await file.arrayBuffer(), file.name);
});
window.addEventListener('dragover', (e) => e.preventDefault());
window.addEventListener('drop', async (e) => {
  e.preventDefault();
  const file = e.dataTransfer?.files?.[0];
  if (file) openModel(await file.arrayBuffer(), file.name);
});

const base64 = (array) => {
  const bytes = new Uint8Array(array.buffer, array.byteOffset, array.byteLength);
  let s = '';
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return btoa(s);
};

// What tests use: the scripted runs (crowd.js) on the loaded model, steering, the live state and
// the timings.
window.live = {
  get ready() { return ready; },
  get version() { return runtime?.version; },
  model: () => model && { joints: model.joints, levels: model.levels, styles: model.styles, min: model.min, max: model.max,
    ignored: [...model.ignored] },
  runScripts(script) {
    const walk = runWalk(runtime, model, { ...script.walk, dt: script.dt });
    const c = runCrowd(runtime, model, { ...script.crowd, dt: script.dt });
    return { walk_states: base64(walk.states), walk_joints: base64(walk.joints), crowd_roots: base64(c.roots),
      crowd_details: base64(c.details), crowd_joints: base64(c.joints) };
  },
  setMode,
  startRecording,
  stopRecording,
  recordedFrames: () => recording?.frames.length ?? 0,
  /// Puts every slider back to the middle of its control's range.
  resetControls() {
    for (const id of ['dz', 'turn', 'dx', 'height']) ui[id].value = '0.5';
    showControls();
  },
  state: () => walker?.readState() ?? null,
  controls: () => model && panelControls(),
  /// The live walker's joints in the world (metres, x y z per joint), for recording a walk.
  worldJoints() {
    if (!walker) return null;
    walker.computeTransforms();
    const f = runtime.f32;
    const s = walker.state >> 2;
    const h = f[s + 15], cx = f[s + 13], cz = f[s + 14];
    const c = Math.cos(h), sn = Math.sin(h);
    const out = [];
    for (let j = 0; j < model.joints; j++) {
      const a = (walker.transforms >> 2) + TRANSFORM_FLOATS * j + 4;
      out.push(c * f[a] + sn * f[a + 2] + cx, f[a + 1], -sn * f[a] + c * f[a + 2] + cz);
    }
    return out;
  },
  timing() {
    const n = Math.max(1, timing.frames);
    return { frames: timing.frames, frameMs: timing.frame / Math.max(1, timing.frames - 1),
      runtimeMs: timing.runtime / n, fkMs: timing.fk / n, drawMs: timing.draw / n,
      levels: [...levelCounts].map((c) => c ?? 0) };
  },
  resetTiming,
  /// Stops (true) or restarts (false) the page's frame loop, so that a benchmark has the machine.
  pause(paused) {
    renderer.setAnimationLoop(paused ? null : frame);
    if (!paused) timing.last = 0;
  },
  /// The pose kernel's median time a call (ns), alone and with FK, at `level` with every joint.
  benchPose: (level) => benchPose(model, { level, joints: model.animatedJoints }),
  /// `mlod_walkers_step`'s median time a walker (ns) for 2,000 walkers, camera facing them (+1)
  /// or away (-1).
  benchStep: (directionZ) => benchStep(model, directionZ),
};

(async () => {
  try {
    runtime = await Runtime.load(await fetch('wasm/motion_lod.wasm'));
  } catch (e) {
    say(`could not start the runtime: ${e.message}`);
    return;
  }
  cameraPtr = runtime.alloc(64);
  ui.version.textContent = `runtime ${runtime.version}`;
  const params = new URLSearchParams(location.search);
  if (params.get('mode') === 'crowd') mode = 'crowd';
  if (params.get('count')) ui.count.value = params.get('count');
  const url = params.get('file') ?? 'model.mlod';
  const r = await fetch(url).catch(() => null);
  if (r?.ok) {
    const served = /filename="([^"]+)"/.exec(r.headers.get('content-disposition') ?? '')?.[1];
    openModel(await r.arrayBuffer(), served ?? url);
  } else {
    say('open a model file (.mlod, from motion-lod build)');
  }
})();
renderer.setAnimationLoop(frame);
