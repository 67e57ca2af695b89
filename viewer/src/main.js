// The prtkit viewer: an `ibl` bake drawn with three.js (skybox, split-sum glTF spheres).
// URL parameters (all optional but ibl):
//   ibl=URL/          folder holding ibl.json (served by viewer/serve.mjs)
//   mode=grid|sphere|sky|equirect   equirect: three's own view of src= (a lat-long .hdr/.exr)
//   src=URL           the source map, for mode=equirect
//   sky=custom|builtin   skybox by our shader (textureLod level 0) or three's scene.background
//   frame=three|gl    three: agree with three.js's cube convention (x negated); gl: raw direction
//   r, m, base=R,G,B  material of mode=sphere (base linear)
//   exposure=EV       linear × 2^EV, no tone mapping, sRGB out (as prtkit render --png)
//   rotate=DEG        environment turn about +Y
//   diffuse=cube|sh   E/π from irradiance.ktx2 or sh.json
//   eye=x,y,z target=x,y,z fov=DEG res=WxH   camera in three.js world coordinates (+Y up)
//   test=1            no UI, no animation loop: the test script drives window.prtkit
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { HDRLoader } from 'three/addons/loaders/HDRLoader.js';
import { EXRLoader } from 'three/addons/loaders/EXRLoader.js';
import { loadPrtkitIbl, PRTKIT_IBL_GLSL, prtkitUniforms } from './prtkit-loader.js';

const q = new URLSearchParams(location.search);
const num = (k, d) => (q.has(k) ? Number(q.get(k)) : d);
const vec = (k, d) => (q.has(k) ? q.get(k).split(',').map(Number) : d);
const test = q.get('test') === '1';
if (test) document.body.classList.add('test');

const state = {
  mode: q.get('mode') ?? 'grid',
  r: num('r', 0.3),
  m: num('m', 1),
  base: vec('base', [1, 0.78, 0.34]),
  exposure: num('exposure', 0),
  rotate: num('rotate', 0),
  diffuse: q.get('diffuse') ?? 'cube',
  frame: q.get('frame') ?? 'three',
  sky: q.get('sky') ?? 'custom',
};
const [W, H] = q.has('res') ? q.get('res').split('x').map(Number) : [innerWidth, innerHeight];

const errors = [];
const errorBox = document.getElementById('error');
function report(msg) {
  errors.push(String(msg));
  console.error(msg);
  errorBox.textContent = errors.join('\n');
}
addEventListener('error', (e) => report(e.message));
addEventListener('unhandledrejection', (e) => report(e.reason?.stack ?? e.reason));

const renderer = new THREE.WebGLRenderer({ antialias: false, alpha: false, preserveDrawingBuffer: test });
renderer.setPixelRatio(test ? 1 : devicePixelRatio);
renderer.setSize(W, H, !test);
renderer.outputColorSpace = THREE.SRGBColorSpace;
renderer.toneMapping = THREE.NoToneMapping;
renderer.debug.checkShaderErrors = true;
renderer.debug.onShaderError = (gl, program, vs, fs) =>
  report('shader error: ' + gl.getProgramInfoLog(program) + gl.getShaderInfoLog(vs) + gl.getShaderInfoLog(fs));
document.body.appendChild(renderer.domElement);
const gl = renderer.getContext();

const camera = new THREE.PerspectiveCamera(num('fov', 45), W / H, 0.05, 200);
const scene = new THREE.Scene();

function placeCamera() {
  const grid = state.mode === 'grid';
  camera.position.fromArray(vec('eye', grid ? [0, 0, 11.5] : [0, 0, 3.6]));
  camera.up.set(0, 1, 0);
  camera.lookAt(new THREE.Vector3().fromArray(vec('target', [0, 0, 0])));
}
placeCamera();

let ibl = null;
const exposureScale = () => Math.pow(2, state.exposure);
const rotation = () => THREE.MathUtils.degToRad(state.rotate);

// --- skybox: the specular chain's level 0, looked up per pixel at lod 0 ---------------------
const skyMaterial = new THREE.ShaderMaterial({
  uniforms: {},
  vertexShader: /* glsl */ `
    varying vec2 vNdc;
    void main() { vNdc = position.xy; gl_Position = vec4(position.xy, 1.0, 1.0); }`,
  fragmentShader: /* glsl */ `
    ${PRTKIT_IBL_GLSL}
    uniform mat4 clipToWorld;
    uniform float exposureScale;
    varying vec2 vNdc;
    void main() {
      vec4 p = clipToWorld * vec4(vNdc, 1.0, 1.0);
      vec3 d = normalize(p.xyz / p.w - cameraPosition);
      vec3 c = textureLod(prtkitSpecular, envFromWorld * d, 0.0).rgb * exposureScale;
      gl_FragColor = linearToOutputTexel(vec4(c, 1.0));
    }`,
  depthTest: false,
  depthWrite: false,
});
const skyGeometry = new THREE.BufferGeometry();
skyGeometry.setAttribute('position', new THREE.Float32BufferAttribute([-1, -1, 0, 3, -1, 0, -1, 3, 0], 3));
const sky = new THREE.Mesh(skyGeometry, skyMaterial);
sky.frustumCulled = false;
sky.renderOrder = -1;

// --- spheres: ray-cast in the fragment shader (exact silhouette and normals, as render's) ----
const sphereVertex = /* glsl */ `
  varying vec3 vWorld;
  void main() {
    vec4 w = modelMatrix * vec4(position, 1.0);
    vWorld = w.xyz;
    gl_Position = projectionMatrix * viewMatrix * w;
  }`;
const sphereFragment = /* glsl */ `
  ${PRTKIT_IBL_GLSL}
  uniform mat4 projectionMatrix; // three declares viewMatrix in fragment shaders, not this one
  uniform vec3 center;
  uniform float radius;
  uniform vec3 baseColor;
  uniform float metalness;
  uniform float roughness;
  uniform float exposureScale;
  varying vec3 vWorld;
  void main() {
    vec3 d = normalize(vWorld - cameraPosition);
    vec3 oc = cameraPosition - center;
    float b = dot(oc, d);
    float h = b * b - (dot(oc, oc) - radius * radius);
    if (h < 0.0) discard;
    float t = -b - sqrt(h);
    if (t < 0.0) discard;
    vec3 hit = cameraPosition + t * d;
    vec3 n = normalize(hit - center);
    vec3 c = prtkitSplitSum(n, -d, baseColor, metalness, roughness) * exposureScale;
    vec4 clip = projectionMatrix * viewMatrix * vec4(hit, 1.0);
    gl_FragDepth = 0.5 * clip.z / clip.w + 0.5;
    gl_FragColor = linearToOutputTexel(vec4(c, 1.0));
  }`;
const spheres = new THREE.Group();
const sphereBox = new THREE.BoxGeometry(2, 2, 2);
function addSphere(center, r, m) {
  const material = new THREE.ShaderMaterial({
    uniforms: {
      ...prtkitUniforms(ibl, rotation()),
      center: { value: new THREE.Vector3(...center) },
      radius: { value: 1 },
      baseColor: { value: new THREE.Color().setRGB(...state.base, THREE.LinearSRGBColorSpace) },
      metalness: { value: m },
      roughness: { value: r },
      exposureScale: { value: exposureScale() },
    },
    vertexShader: sphereVertex,
    fragmentShader: sphereFragment,
    side: THREE.BackSide, // the far faces of the box: fragments even when the near ones are clipped
  });
  const mesh = new THREE.Mesh(sphereBox, material);
  mesh.position.set(...center);
  spheres.add(mesh);
}
const GRID_R = [0, 0.25, 0.5, 0.75, 1];
const GRID_M = [0, 1];
function buildSpheres() {
  spheres.clear();
  if (state.mode === 'sphere') addSphere([0, 0, 0], state.r, state.m);
  if (state.mode === 'grid') {
    GRID_M.forEach((m, j) => GRID_R.forEach((r, i) => addSphere([(i - 2) * 2.4, (0.5 - j) * 2.4, 0], r, m)));
  }
}

function updateUniforms() {
  const common = prtkitUniforms(ibl, rotation());
  for (const material of [skyMaterial, ...spheres.children.map((s) => s.material)]) {
    for (const [k, v] of Object.entries(common)) {
      if (material.uniforms[k]) material.uniforms[k].value = v.value;
      else material.uniforms[k] = v;
    }
    material.uniforms.prtkitDiffuseFromSh.value = state.diffuse === 'sh' ? 1 : 0;
    (material.uniforms.exposureScale ??= { value: 1 }).value = exposureScale();
  }
  for (const s of spheres.children) {
    if (state.mode === 'sphere') {
      s.material.uniforms.roughness.value = state.r;
      s.material.uniforms.metalness.value = state.m;
    }
  }
  scene.backgroundIntensity = exposureScale();
  scene.backgroundRotation.set(0, rotation(), 0);
}

async function loadEquirect(url) {
  const loader = url.toLowerCase().endsWith('.exr') ? new EXRLoader() : new HDRLoader();
  const texture = await loader.loadAsync(url);
  texture.mapping = THREE.EquirectangularReflectionMapping;
  return texture;
}

async function setup() {
  scene.clear();
  scene.background = null;
  if (state.mode === 'equirect') {
    // three.js's own view of the source lat-long map: the reference of the skybox test.
    scene.background = await loadEquirect(q.get('src'));
    scene.backgroundIntensity = exposureScale();
    scene.backgroundRotation.set(0, rotation(), 0);
    return;
  }
  if (!ibl || ibl.frame !== state.frame) {
    const url = q.get('ibl');
    if (!url) throw new Error('give the bake folder: ?ibl=/path/to/ibl/ (scripts/view.sh DIR does it)');
    ibl = await loadPrtkitIbl(url, { frame: state.frame });
    document.getElementById('source').textContent = ibl.manifest.source.split('/').pop();
  }
  buildSpheres();
  if (state.sky === 'builtin') {
    // three's own skybox path with the loader's cube: it negates x itself (frame=three only).
    scene.background = ibl.background;
  } else {
    scene.add(sky);
  }
  scene.add(spheres);
  updateUniforms();
}

function draw() {
  camera.updateMatrixWorld();
  (skyMaterial.uniforms.clipToWorld ??= { value: new THREE.Matrix4() }).value.multiplyMatrices(camera.matrixWorld, camera.projectionMatrixInverse);
  renderer.render(scene, camera);
  const e = gl.getError();
  if (e !== gl.NO_ERROR) report(`WebGL error 0x${e.toString(16)}`);
}

// --- test hooks ---------------------------------------------------------------------------
function pixels() {
  draw();
  const buf = new Uint8Array(W * H * 4);
  gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, buf);
  let s = '';
  for (let i = 0; i < buf.length; i += 0x8000) s += String.fromCharCode.apply(null, buf.subarray(i, i + 0x8000));
  return { width: W, height: H, rgbaBottomUp: btoa(s) };
}
function bench(frames = 30) {
  const one = new Uint8Array(4);
  draw();
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, one);
  const t0 = performance.now();
  for (let i = 0; i < frames; i++) {
    state.rotate = (state.rotate + 1) % 360; // a turning environment: uniforms change every frame
    updateUniforms();
    draw();
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, one); // wait for the GPU (SwiftShader: the CPU)
  }
  return (performance.now() - t0) / frames;
}
window.prtkit = {
  errors,
  ready: setup().then(() => { draw(); return true; }).catch((e) => { report(e.stack ?? e); return false; }),
  pixels,
  bench,
  gpu: () => {
    const ext = gl.getExtension('WEBGL_debug_renderer_info');
    return ext ? gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
  },
};

// --- interactive ---------------------------------------------------------------------------
if (!test) {
  const controls = new OrbitControls(camera, renderer.domElement);
  const el = (id) => document.getElementById(id);
  for (const id of ['mode', 'r', 'm', 'exposure', 'rotate', 'diffuse', 'frame']) el(id).value = state[id];
  const stats = el('stats');
  const rebuild = async () => { await setup(); };
  el('mode').onchange = (e) => { state.mode = e.target.value; placeCamera(); controls.update(); rebuild(); };
  el('frame').onchange = (e) => { state.frame = e.target.value; rebuild(); };
  for (const id of ['r', 'm', 'exposure', 'rotate']) el(id).oninput = (e) => { state[id] = Number(e.target.value); if (ibl) updateUniforms(); };
  el('diffuse').onchange = (e) => { state.diffuse = e.target.value; if (ibl) updateUniforms(); };
  addEventListener('resize', () => {
    camera.aspect = innerWidth / innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(innerWidth, innerHeight);
  });
  let last = performance.now(), avg = 0;
  renderer.setAnimationLoop(() => {
    const now = performance.now();
    avg = avg ? 0.95 * avg + 0.05 * (now - last) : now - last;
    last = now;
    controls.update();
    draw();
    stats.textContent = `${avg.toFixed(1)} ms/frame (${(1000 / avg).toFixed(0)} fps), ${renderer.info.render.calls} draws`;
    stats.title = window.prtkit.gpu();
  });
}
