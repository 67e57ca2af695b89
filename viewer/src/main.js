// The prtkit viewer: an `ibl` bake drawn with three.js (skybox, split-sum glTF spheres).
// URL parameters (all optional but ibl):
//   ibl=URL/          folder holding ibl.json (served by viewer/serve.mjs)
//   mode=grid|sphere|sky|equirect   equirect: three's own view of src= (a lat-long .hdr/.exr)
//   mode=model        model=URL (.gltf/.glb by GLTFLoader, .obj by OBJLoader) lit by the split sum:
//                     glTF materials keep their base colour/metalness/roughness (factors and
//                     textures), an OBJ takes r, m, base; up=y|z the model's up axis (glTF: y;
//                     OBJ default z, prtkit's meshes)
//   src=URL           the source map, for mode=equirect
//   sky=custom|builtin   skybox by our shader (textureLod level 0) or three's scene.background
//   frame=three|gl    three: agree with three.js's cube convention (x negated); gl: raw direction
//   r, m, base=R,G,B  material of mode=sphere (base linear)
//   exposure=EV       linear × 2^EV, no tone mapping, sRGB out (as prtkit render --png)
//   rotate=DEG        environment turn about +Y
//   diffuse=cube|sh   E/π from irradiance.ktx2 or sh.json
//   eye=x,y,z target=x,y,z fov=DEG res=WxH   camera in three.js world coordinates (+Y up)
//   mode=irradiance   sh=URL (sh-project's prtkit.sh): a Lambert sphere lit by E(n) (albedo=A, default 1)
//   mode=shrm         shrm=URL (prefilter's prtkit.shrm; its EXR beside it): per-pixel SHRM sphere
//   mode=normals      codes=URL report=URL decoder=URL (encode-normals' codes, report, --emit-decoder
//                     glsl) size=WxH: a lat-long table of normals decoded in the shader, lit by sh=URL
//   mode=prt          glb=URL (transfer --glb) sh=URL (sh-project of the map, order ≥ the bake's n − 1):
//                     the mesh relit per vertex, B = Σ_i T_i L_i, Gouraud; a glossy bake (transfer
//                     --factors) also needs glsl=URL (its transfer --glsl snippet): c_k per vertex,
//                     B = Σ_k h_k(Fᵀω_o) c_k per pixel; a bake compressed by clustered PCA
//                     (transfer --clusters C --pca P) is relit in compressed form, either kind
//   (these four: frame=three|gl as above; src=URL shows three's equirect view of the map behind;
//    rotate=DEG turns the lighting about the up axis: SH coefficients rotated every frame)
//   test=1            no UI, no animation loop: the test script drives window.prtkit
// Files and folders dropped on the page open as their URLs would (object URLs; see openFiles).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { HDRLoader } from 'three/addons/loaders/HDRLoader.js';
import { EXRLoader } from 'three/addons/loaders/EXRLoader.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OBJLoader } from 'three/addons/loaders/OBJLoader.js';
import { MTLLoader } from 'three/addons/loaders/MTLLoader.js';
import { loadPrtkitIbl, PRTKIT_IBL_GLSL, prtkitUniforms } from './prtkit-loader.js';
import { prtkitFromWorld, loadPrtkitSh, rotateShZ, irradianceUniform, SH_GLSL, loadPrtkitShrm, SHRM_GLSL, loadNormalCodes,
  prtAttribute, transferLightingUniform, prtVertexShader, PRT_FRAGMENT,
  transferTexture, glossyHTexture, prtGlossyVertexShader, prtGlossyFragmentShader, prtTextureVertexShader,
  PRT_CLUSTER_ATTRIBUTE, prtWeightAttribute, cpcaBake, projectCpcaLighting, prtCpcaVertexShader } from './prtkit-sh.js';
import { readFrame } from './readback.js';

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
// The lines every sphere shader shares: the view ray d through this fragment meets the sphere
// (center, radius) at \`hit\` with normal n, or the fragment is discarded; the depth written is
// the hit's, so spheres occlude each other exactly.
const SPHERE_HIT = /* glsl */ `
    vec3 d = normalize(vWorld - cameraPosition);
    vec3 oc = cameraPosition - center;
    float b = dot(oc, d);
    float h = b * b - (dot(oc, oc) - radius * radius);
    if (h < 0.0) discard;
    float t = -b - sqrt(h);
    if (t < 0.0) discard;
    vec3 hit = cameraPosition + t * d;
    vec3 n = normalize(hit - center);`;
const SPHERE_DEPTH = /* glsl */ `
    vec4 clip = projectionMatrix * viewMatrix * vec4(hit, 1.0);
    gl_FragDepth = 0.5 * clip.z / clip.w + 0.5;`;
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
    ${SPHERE_HIT}
    vec3 c = prtkitSplitSum(n, -d, baseColor, metalness, roughness) * exposureScale;
    ${SPHERE_DEPTH}
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
// --- models (mode=model): a glTF/GLB or OBJ lit by the same split sum as the spheres ---------
// The vertex normal (world space, through the inverse transpose) replaces the ray-cast one; the
// shading is the spheres' prtkitSplitSum. glTF metal/rough materials keep their own base colour,
// metalness and roughness, factors times textures (baseColorTexture in .rgb, sRGB, decoded by
// three; metallicRoughnessTexture's .g roughness, .b metalness, glTF 2.0 §3.9.2); normal,
// occlusion and emissive textures are not applied. An OBJ gets the panel's r, m and base.
const modelVertex = /* glsl */ `
  varying vec3 vWorld;
  varying vec3 vNormal;
  varying vec2 vUv;
  void main() {
    vec4 w = modelMatrix * vec4(position, 1.0);
    vWorld = w.xyz;
    vNormal = transpose(inverse(mat3(modelMatrix))) * normal;
    vUv = uv;
    gl_Position = projectionMatrix * viewMatrix * w;
  }`;
const modelFragment = /* glsl */ `
  ${PRTKIT_IBL_GLSL}
  uniform vec3 baseColor;
  uniform float metalness;
  uniform float roughness;
  uniform float exposureScale;
  uniform sampler2D baseColorMap;
  uniform sampler2D metalRoughMap;
  varying vec3 vWorld;
  varying vec3 vNormal;
  varying vec2 vUv;
  void main() {
    vec3 n = normalize(vNormal);
    if (!gl_FrontFacing) n = -n; // a double-sided glTF material, or an OBJ wound inwards
    vec3 v = normalize(cameraPosition - vWorld);
    vec3 base = baseColor;
    float m = metalness, r = roughness;
  #ifdef USE_BASE_MAP
    base *= texture(baseColorMap, vUv).rgb;
  #endif
  #ifdef USE_MR_MAP
    vec4 mr = texture(metalRoughMap, vUv);
    r *= mr.g;
    m *= mr.b;
  #endif
    vec3 c = prtkitSplitSum(n, v, base, clamp(m, 0.0, 1.0), clamp(r, 0.0, 1.0)) * exposureScale;
    gl_FragColor = linearToOutputTexel(vec4(c, 1.0));
  }`;
const model = { object: null, materials: [], fromObj: false, mtl: false, key: '' };
// The model's file type: by the URL's extension, or `type=` (object URLs of dropped files have none).
const modelKind = (url, type) => (type ?? url.split(/[?#]/)[0].split('.').pop()).toLowerCase();
async function loadModel(url, type = q.get('type') ?? undefined, manager = undefined) {
  const kind = modelKind(url, type);
  if (kind === 'obj') return loadObj(url, manager);
  if (kind === 'gltf' || kind === 'glb') return { object: (await new GLTFLoader(manager).loadAsync(url)).scene, fromObj: false, mtl: false };
  throw new Error(`model=${url}: .gltf, .glb or .obj (or give type=gltf|glb|obj)`);
}
// An OBJ and the material library its `mtllib` names (three's MTLLoader: Kd, sRGB-encoded, and
// map_Kd, an sRGB image, become the base colour; the rest of the library is not used). The library
// is beside the OBJ (a dropped one: found by name, through the manager's URL modifier), its
// textures beside the library; they are waited for, so the first frame has them.
async function loadObj(url, manager) {
  const r = await fetch(manager?.resolveURL(url) ?? url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  const text = await r.text();
  const library = /^mtllib[ \t]+(.+?)[ \t]*$/m.exec(text)?.[1];
  const loader = new OBJLoader(manager);
  if (library) {
    const at = url.startsWith('blob:') ? library : new URL(library, new URL(url, location.href)).href;
    const materials = await new MTLLoader(manager).loadAsync(at).catch((e) => {
      throw new Error(`${url}: its material library ${library}: ${e.message ?? e}`);
    });
    const textures = new THREE.LoadingManager();
    if (manager) textures.setURLModifier((u) => manager.resolveURL(u));
    let started = false;
    textures.onStart = () => { started = true; };
    const loaded = new Promise((ok, fail) => {
      textures.onLoad = ok;
      textures.onError = (u) => fail(new Error(`${url}: ${library}: texture ${u} not loaded`));
    });
    materials.setManager(textures);
    materials.preload(); // starts the texture loads
    if (started) await loaded;
    loader.setMaterials(materials);
  }
  return { object: loader.parse(text), fromObj: true, mtl: Boolean(library) };
}
function modelMaterial(source, fromObj) {
  const defines = {};
  const uniforms = {
    ...prtkitUniforms(ibl, rotation()),
    baseColor: { value: new THREE.Color().setRGB(...state.base, THREE.LinearSRGBColorSpace) },
    metalness: { value: state.m },
    roughness: { value: state.r },
    exposureScale: { value: exposureScale() },
    baseColorMap: { value: null },
    metalRoughMap: { value: null },
  };
  if (fromObj && model.mtl) { // the library's Kd (linear, as MTLLoader keeps it) and map_Kd
    uniforms.baseColor.value.copy(source.color);
    if (source.map) { uniforms.baseColorMap.value = source.map; defines.USE_BASE_MAP = ''; }
  }
  if (!fromObj && source?.isMeshStandardMaterial) {
    uniforms.baseColor.value.copy(source.color); // linear: glTF's baseColorFactor is, and three keeps it so
    uniforms.metalness.value = source.metalness;
    uniforms.roughness.value = source.roughness;
    if (source.map) { uniforms.baseColorMap.value = source.map; defines.USE_BASE_MAP = ''; }
    if (source.roughnessMap || source.metalnessMap) {
      uniforms.metalRoughMap.value = source.roughnessMap ?? source.metalnessMap;
      defines.USE_MR_MAP = '';
    }
  }
  const material = new THREE.ShaderMaterial({ uniforms, defines, vertexShader: modelVertex, fragmentShader: modelFragment,
    side: fromObj ? THREE.DoubleSide : (source?.side ?? THREE.FrontSide) });
  material.userData.fromObj = fromObj;
  return material;
}
async function buildModel() {
  const url = q.get('model');
  if (!url) throw new Error('mode=model needs model=URL (.gltf, .glb or .obj)');
  if (model.key !== url) {
    Object.assign(model, await loadModel(url, q.get('type') ?? undefined, dropped.manager()), { key: url });
    const up = q.get('up') ?? (model.fromObj ? 'z' : 'y');
    if (up === 'z') { // prtkit's +Z-up axes into three's +Y-up world: (x, y, z) → (x, z, −y)
      model.object.matrixAutoUpdate = false;
      model.object.matrix.set(1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 1);
    } else if (up !== 'y') throw new Error(`up=${up}: y or z`);
    model.object.traverse((o) => {
      if (!o.isMesh) return;
      if (!o.geometry.attributes.normal) o.geometry.computeVertexNormals();
    });
  }
  model.materials = [];
  model.object.traverse((o) => {
    if (!o.isMesh) return;
    o.userData.source ??= o.material;
    const make = (m) => { const mm = modelMaterial(m, model.fromObj); model.materials.push(mm); return mm; };
    o.material = Array.isArray(o.userData.source) ? o.userData.source.map(make) : make(o.userData.source);
  });
  spheres.clear();
  spheres.add(model.object);
  if (!q.has('eye')) { // frame the model: its bounding sphere fills the view
    model.object.updateMatrixWorld(true);
    const s = new THREE.Box3().setFromObject(model.object).getBoundingSphere(new THREE.Sphere());
    const d = s.radius / Math.sin(THREE.MathUtils.degToRad(camera.fov) / 2) * 1.1;
    camera.position.copy(s.center).add(new THREE.Vector3(0, 0, d));
    camera.lookAt(s.center);
    window.prtkitControls?.target.copy(s.center);
  }
  document.getElementById('source').textContent = `${ibl.manifest.source.split('/').pop()}, ${url.split('/').pop()}`;
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


// --- SH irradiance, SHRM and encoded-normal spheres (prtkit-sh.js) ---------------------------
// Ray-cast like the split-sum spheres; each mode's shading works in prtkit's frame
// (prtkitFromWorld: see prtkit-sh.js's header).
const SH_MODES = ['irradiance', 'shrm', 'normals', 'prt'];
const docs = {}; // what each mode loaded: sh, shrm, codes, decoder
const shadeBody = {
  irradiance: 'c = prtkitShLambert(prtkitFromWorld * n);',
  shrm: `vec3 np = prtkitFromWorld * n, wo = prtkitFromWorld * (-d);
         c = prtkitShrm(reflect(-wo, np), wo);`,
  normals: 'c = prtkitShLambert(decodedNormal(prtkitFromWorld * n));',
};
const NORMALS_GLSL = /* glsl */ `
precision highp usampler2D;
uniform usampler2D codes;
// The lat-long table of normals, texel (x, y) at φ = 2π(x + ½)/W, θ = π(y + ½)/H: the four
// nearest codes decoded and blended bilinearly (wrapping in φ), then normalized.
vec3 decodedAt(ivec2 t, ivec2 size) {
  t.x = (t.x + size.x) % size.x;
  t.y = clamp(t.y, 0, size.y - 1);
  return prtkit_decode_normal(texelFetch(codes, t, 0).r);
}
vec3 decodedNormal(vec3 g) {
  ivec2 size = textureSize(codes, 0);
  float phi = atan(g.y, g.x);
  vec2 f = vec2((phi < 0.0 ? phi + 6.283185307179586 : phi) / 6.283185307179586, acos(clamp(g.z, -1.0, 1.0)) / 3.141592653589793) * vec2(size) - 0.5;
  ivec2 i = ivec2(floor(f));
  vec2 w = f - floor(f);
  vec3 n = mix(mix(decodedAt(i, size), decodedAt(i + ivec2(1, 0), size), w.x),
               mix(decodedAt(i + ivec2(0, 1), size), decodedAt(i + ivec2(1, 1), size), w.x), w.y);
  return normalize(n);
}`;
function shFragment(mode) {
  const head = mode === 'shrm' ? `uniform mat3 prtkitFromWorld;\n${SHRM_GLSL}`
    : SH_GLSL + (mode === 'normals' ? docs.decoder + NORMALS_GLSL : '');
  return /* glsl */ `
  ${head}
  uniform mat4 projectionMatrix;
  uniform vec3 center;
  uniform float radius;
  uniform float exposureScale;
  varying vec3 vWorld;
  void main() {
    ${SPHERE_HIT}
    vec3 c = vec3(0.0);
    ${shadeBody[mode]}
    ${SPHERE_DEPTH}
    gl_FragColor = linearToOutputTexel(vec4(c * exposureScale, 1.0));
  }`;
}
let shMaterial = null;
async function setupShMode() {
  const mode = state.mode;
  if (mode === 'irradiance' || mode === 'normals' || mode === 'prt') {
    const url = q.get('sh');
    if (!url) throw new Error(`mode=${mode} needs sh=URL (a prtkit.sh document from sh-project)`);
    docs.sh ??= await loadPrtkitSh(url);
  }
  if (mode === 'shrm') {
    const url = q.get('shrm');
    if (!url) throw new Error('mode=shrm needs shrm=URL (a prtkit.shrm document from prefilter --shrm)');
    docs.shrm ??= await loadPrtkitShrm(url, dropped.urls.size ? dropped.urlOf : undefined);
    document.getElementById('source').textContent = docs.shrm.doc.brdf;
  }
  if (mode === 'normals') {
    for (const k of ['codes', 'report', 'decoder', 'size']) if (!q.get(k)) throw new Error(`mode=normals needs ${k}=`);
    const [w, h] = q.get('size').split('x').map(Number);
    docs.codes ??= await loadNormalCodes(q.get('codes'), q.get('report'), w, h);
    docs.decoder ??= await (await fetch(q.get('decoder'))).text();
  }
  const uniforms = {
    center: { value: new THREE.Vector3(0, 0, 0) },
    radius: { value: 1 },
    exposureScale: { value: exposureScale() },
    prtkitFromWorld: { value: prtkitFromWorld(state.frame) },
    shIrradiance: { value: irradianceUniform([], 1) },
    shrmLayers: { value: docs.shrm?.texture ?? null },
    shrmPB: { value: docs.shrm?.pb ?? 0 },
    shrmGlobal: { value: docs.shrm?.global ? 1 : 0 },
    envTurn: { value: 0 },
    codes: { value: docs.codes?.texture ?? null },
  };
  spheres.clear();
  if (mode === 'prt') {
    spheres.add(await prtMesh(uniforms));
  } else {
    shMaterial = new THREE.ShaderMaterial({ uniforms, vertexShader: sphereVertex, fragmentShader: shFragment(mode), side: THREE.BackSide });
    spheres.add(new THREE.Mesh(sphereBox, shMaterial));
  }
  scene.add(spheres);
  if (q.get('src')) scene.background = await loadEquirect(q.get('src'));
}
// mode=prt: the transfer .glb (positions in prtkit's frame) placed in three's world by the inverse
// (transpose) of prtkitFromWorld, so the lighting SH stays in prtkit's frame as render has it.
async function prtMesh(uniforms) {
  const url = q.get('glb');
  if (!url) throw new Error('mode=prt needs glb=URL (a transfer --glb bake) and sh=URL (sh-project of the map)');
  docs.prt ??= await new GLTFLoader().loadAsync(url);
  let mesh = null;
  docs.prt.scene.traverse((o) => { if (o.isMesh) mesh = o; });
  if (!mesh) throw new Error(`${url}: no mesh`);
  const bake = mesh.userData['prtkit.transfer'];
  if (bake?.quantization) await dequantizeTransfer(url, mesh, bake.quantization);
  // A coloured bake (transfer --albedo R,G,B or mesh) holds one transfer vector per channel.
  docs.prtChannels = bake?.channels ?? 1;
  docs.prtCoeffs = (bake?.order ?? 0) ** 2;
  if (bake?.cpca) return prtCpcaMesh(url, mesh, bake, uniforms);
  let K = 0;
  while (mesh.geometry.attributes[prtAttribute(K)]) K++;
  if (!bake || K === 0) throw new Error(`${url}: not a transfer bake (no prtkit.transfer extras or _PRT_k attributes)`);
  if (bake.glossy) return prtGlossyMesh(url, mesh, bake, uniforms);
  if (docs.sh.coefficients.length < bake.order ** 2) throw new Error(`sh: order ${docs.sh.order} < the bake's ${bake.order} bands − 1`);
  uniforms.shLighting = { value: transferLightingUniform([], 4 * K) };
  // Position and K four-vectors within the attributes the device draws (16 guaranteed: n ≤ 7);
  // past that, the transfer is read from a texture by gl_VertexID.
  const inAttributes = K + 1 <= gl.getParameter(gl.MAX_VERTEX_ATTRIBS);
  document.getElementById('source').textContent =
    `${url.split('/').pop()}: n = ${bake.order}, ${bake.mode}${docs.prtChannels === 3 ? ', RGB transfer' : ''}${inAttributes ? '' : `, transfer read from a texture (${K} texels a vertex)`}`;
  if (!inAttributes) uniforms.prtTransfer = { value: (docs.prtTexture ??= transferTexture(mesh.geometry, K)) };
  const vertexShader = inAttributes ? prtVertexShader(K) : prtTextureVertexShader(K);
  shMaterial = new THREE.ShaderMaterial({ uniforms, vertexShader, fragmentShader: PRT_FRAGMENT, side: THREE.DoubleSide });
  const object = new THREE.Mesh(mesh.geometry, shMaterial);
  object.matrixAutoUpdate = false;
  object.matrix.setFromMatrix3(prtkitFromWorld(state.frame).transpose());
  return object;
}
// A quantized bake (transfer --quantize i16|i8): GLTFLoader gives its _PRT_k (compressed: _PRT_W_k)
// as normalized SHORT/BYTE attributes, read as max(code / q, −1); each value is that times its
// scale, per value index, or per cluster with CPCA (docs/formats/transfer.md, "Quantized
// bakes"). Applied once, on load, into float attributes, so every relighting path below takes
// the values as from a float bake; an engine would rather fold the scales into the lighting or
// dequantize in its shader (the bake's snippets do).
async function dequantizeTransfer(url, mesh, quant) {
  const geometry = mesh.geometry;
  if (geometry.userData.prtkitDequantized) return;
  const blob = mesh.userData['prtkit.blobs']?.[quant.scales];
  if (!blob) throw new Error(`${url}: a quantized bake without its ${quant.scales} blob`);
  const scales = new Float32Array(await docs.prt.parser.getDependency('bufferView', blob.bufferView), 0, blob.count);
  const attrs = geometry.attributes;
  const cluster = quant.scale_per === 'cluster' ? attrs[PRT_CLUSTER_ATTRIBUTE] : null;
  if (quant.scale_per === 'cluster' && !cluster) throw new Error(`${url}: scales per cluster but no ${PRT_CLUSTER_ATTRIBUTE}`);
  const name = cluster ? prtWeightAttribute : prtAttribute;
  for (let k = 0; attrs[name(k)]; k++) {
    const a = attrs[name(k)];
    if (!a.normalized) throw new Error(`${url}: ${name(k)} is not a normalized attribute, though the extras say ${quant.type}`);
    const values = new Float32Array(4 * a.count);
    for (let v = 0; v < a.count; v++) {
      for (let j = 0; j < 4; j++) {
        const scale = cluster ? scales[cluster.getX(v)] : scales[4 * k + j] ?? 0;
        values[4 * v + j] = Math.max(a.getComponent(v, j), -1) * scale;
      }
    }
    geometry.setAttribute(name(k), new THREE.BufferAttribute(values, 4));
  }
  geometry.userData.prtkitDequantized = true;
}
// mode=prt with a glossy bake (extras.prtkit.transfer.glossy): Mahajan, Tseng & Ramamoorthi
// 2008's eq. 4, B(x, ω_o) = Σ_k h_k(Fᵀω_o) c_k(x). The K·n² values per vertex go to a float
// texture read by gl_VertexID (c_k = Σ_i T_ki L_i in the vertex shader), h_k to an R32F texture
// (the .glb's glossy.h blob as it is), and the per-pixel sum is the emitted snippet's
// prtkitGlossyRadiance (glsl=URL: `transfer --glsl` of this bake), so the page runs the
// shipped lookup itself.
async function prtGlossyMesh(url, mesh, bake, uniforms) {
  const g = bake.glossy;
  const coeffs = bake.order ** 2, K = g.terms;
  if (!q.get('glsl')) throw new Error(`${url}: a glossy bake; mode=prt needs glsl=URL too (its transfer --glsl snippet, which holds the h_k lookup)`);
  if (docs.sh.coefficients.length < coeffs) throw new Error(`sh: order ${docs.sh.order} < the bake's ${bake.order} bands − 1`);
  const varyings = Math.ceil((3 * K) / 4) + 2;
  const limit = gl.getParameter(gl.MAX_VARYING_VECTORS);
  if (varyings > limit) throw new Error(`${url}: K = ${K} terms need ${varyings} varying vectors; this device has ${limit}`);
  if (!docs.glossy) {
    const blob = mesh.userData['prtkit.blobs']?.['glossy.h'];
    if (!blob) throw new Error(`${url}: a glossy bake without its glossy.h blob`);
    const view = await docs.prt.parser.getDependency('bufferView', blob.bufferView);
    const snippet = await (await fetch(q.get('glsl'))).text();
    if (!snippet.includes(`#define PRTKIT_GLOSSY_TERMS ${K}\n`) || !snippet.includes(`#define PRTKIT_GLOSSY_RESOLUTION ${g.resolution}\n`)) {
      throw new Error(`${q.get('glsl')}: not the glossy snippet of this bake (K = ${K}, ${g.resolution}² cells)`);
    }
    docs.glossy = {
      transfer: transferTexture(mesh.geometry, Math.ceil((K * coeffs) / 4)),
      h: glossyHTexture(new Float32Array(view, 0, blob.count), g.resolution, K),
      snippet,
    };
  }
  document.getElementById('source').textContent = `${url.split('/').pop()}: n = ${bake.order}, ${bake.mode}, glossy ${g.brdf}, K = ${K}`;
  uniforms.shLighting = { value: transferLightingUniform([], coeffs) };
  uniforms.prtTransfer = { value: docs.glossy.transfer };
  uniforms.prtkitGlossyHTexture = { value: docs.glossy.h };
  shMaterial = new THREE.ShaderMaterial({ uniforms, vertexShader: prtGlossyVertexShader(K, coeffs),
    fragmentShader: prtGlossyFragmentShader(docs.glossy.snippet, K), side: THREE.DoubleSide });
  const object = new THREE.Mesh(mesh.geometry, shMaterial);
  object.matrixAutoUpdate = false;
  object.matrix.setFromMatrix3(prtkitFromWorld(state.frame).transpose());
  return object;
}
// mode=prt with a bake compressed by clustered PCA (extras.prtkit.transfer.cpca; transfer
// --clusters C --pca P), diffuse or glossy, relit in compressed form (Sloan et al. 2003, eq. 3):
// every frame the CPU dots the turned lighting with each cluster's mean and P directions, term
// by term (projectCpcaLighting), into a small float texture; the vertex shader takes its
// cluster's texels and P multiply-adds per term. A glossy bake's c_k then go to the same
// fragment shader as an uncompressed one's.
async function prtCpcaMesh(url, mesh, bake, uniforms) {
  const { clusters: C, components: P } = bake.cpca;
  const coeffs = bake.order ** 2, g = bake.glossy, K = g ? g.terms : 1;
  const attrs = mesh.geometry.attributes, A = Math.ceil(P / 4);
  if (!attrs[PRT_CLUSTER_ATTRIBUTE]) throw new Error(`${url}: a compressed bake without _PRT_CLUSTER`);
  for (let a = 0; a < A; a++) if (!attrs[prtWeightAttribute(a)]) throw new Error(`${url}: a compressed bake of P = ${P} without _PRT_W_${a}`);
  // position, the cluster, ⌈P/4⌉ weight vectors (and the normal, glossy) of WebGL 2's 16 attributes.
  const used = 2 + A + (g ? 1 : 0), limit = gl.getParameter(gl.MAX_VERTEX_ATTRIBS);
  if (used > limit) throw new Error(`${url}: P = ${P} weights need ${used} vertex attributes; this device has ${limit}`);
  if (docs.sh.coefficients.length < coeffs) throw new Error(`sh: order ${docs.sh.order} < the bake's ${bake.order} bands − 1`);
  if (g) {
    if (!q.get('glsl')) throw new Error(`${url}: a glossy bake; mode=prt needs glsl=URL too (its transfer --glsl snippet, which holds the h_k lookup)`);
    const varyings = Math.ceil((3 * K) / 4) + 2, vlimit = gl.getParameter(gl.MAX_VARYING_VECTORS);
    if (varyings > vlimit) throw new Error(`${url}: K = ${K} terms need ${varyings} varying vectors; this device has ${vlimit}`);
  }
  if (!docs.cpca) {
    const blobs = mesh.userData['prtkit.blobs'] ?? {};
    const floats = async (name) => {
      if (!blobs[name]) throw new Error(`${url}: a compressed bake without its ${name} blob`);
      const view = await docs.prt.parser.getDependency('bufferView', blobs[name].bufferView);
      return new Float32Array(view, 0, blobs[name].count);
    };
    docs.cpca = cpcaBake(C, P, K, coeffs, await floats('cpca.means'), await floats('cpca.bases'), docs.prtChannels);
    if (g) {
      const snippet = await (await fetch(q.get('glsl'))).text();
      if (!snippet.includes(`#define PRTKIT_GLOSSY_TERMS ${K}\n`) || !snippet.includes(`#define PRTKIT_GLOSSY_RESOLUTION ${g.resolution}\n`)) {
        throw new Error(`${q.get('glsl')}: not the glossy snippet of this bake (K = ${K}, ${g.resolution}² cells)`);
      }
      docs.glossy = { h: glossyHTexture(await floats('glossy.h'), g.resolution, K), snippet };
    }
  }
  document.getElementById('source').textContent = `${url.split('/').pop()}: n = ${bake.order}, ${bake.mode}${g ? `, glossy ${g.brdf}, K = ${K}` : ''}, CPCA ${C} clusters × ${P}`;
  uniforms.cpcaLighting = { value: docs.cpca.texture };
  const material = g
    ? { vertexShader: prtCpcaVertexShader(K, P, true), fragmentShader: prtGlossyFragmentShader(docs.glossy.snippet, K) }
    : { vertexShader: prtCpcaVertexShader(1, P, false), fragmentShader: PRT_FRAGMENT };
  if (g) uniforms.prtkitGlossyHTexture = { value: docs.glossy.h };
  shMaterial = new THREE.ShaderMaterial({ uniforms, ...material, side: THREE.DoubleSide });
  const object = new THREE.Mesh(mesh.geometry, shMaterial);
  object.matrixAutoUpdate = false;
  object.matrix.setFromMatrix3(prtkitFromWorld(state.frame).transpose());
  return object;
}
// Every frame: the lighting turned by state.rotate about the up axis. For SH lighting the
// coefficients themselves are rotated (rotateShZ, any order); the SHRM's lookup turns (β − γ).
function updateShUniforms() {
  const u = shMaterial.uniforms;
  const turn = rotation();
  u.exposureScale.value = exposureScale();
  u.prtkitFromWorld.value = prtkitFromWorld(state.frame);
  if (docs.sh && u.cpcaLighting) projectCpcaLighting(docs.cpca, rotateShZ(docs.sh.coefficients, turn));
  else if (docs.sh && u.shLighting) {
    const turned = rotateShZ(docs.sh.coefficients, turn);
    u.shLighting.value = transferLightingUniform(turned, u.shLighting.value.length, docs.prtChannels ?? 1, docs.prtCoeffs);
  }
  else if (docs.sh) u.shIrradiance.value = irradianceUniform(rotateShZ(docs.sh.coefficients, turn), num('albedo', 1));
  u.envTurn.value = turn;
  scene.backgroundIntensity = exposureScale();
  // three's equirect background turns the map by +angle about +Y; prtkit's +Z turn by γ is a turn
  // by −γ about three's +Y in the mirrored (three) frame.
  scene.backgroundRotation.set(0, state.frame === 'three' ? -turn : turn, 0);
}
// Test hooks that run a fragment shader once per texel of a width × height RGBA32F target (a
// full-screen triangle; gl_FragCoord.xy is the texel) and read the floats back, row 0 first.
function renderFloats(fragmentShader, uniforms, width, height) {
  const target = new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType, format: THREE.RGBAFormat, depthBuffer: false });
  const material = new THREE.ShaderMaterial({
    uniforms,
    vertexShader: 'void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }',
    fragmentShader,
  });
  const quad = new THREE.Mesh(skyGeometry, material);
  quad.frustumCulled = false;
  const s = new THREE.Scene();
  s.add(quad);
  renderer.setRenderTarget(target);
  renderer.render(s, camera);
  const buf = new Float32Array(width * height * 4);
  renderer.readRenderTargetPixels(target, 0, 0, width, height, buf);
  renderer.setRenderTarget(null);
  target.dispose();
  material.dispose();
  return buf;
}
// Test hook: the code table decoded on the GPU by the emitted decoder, one texel per code;
// returns the xyz as a flat array (row 0 = the first W codes).
function decodedNormals() {
  const tex = docs.codes.texture;
  const { width, height } = tex.image;
  const buf = renderFloats(`${docs.decoder}
      precision highp usampler2D;
      uniform usampler2D codes;
      void main() { gl_FragColor = vec4(prtkit_decode_normal(texelFetch(codes, ivec2(gl_FragCoord.xy), 0).r), 1.0); }`,
  { codes: { value: tex } }, width, height);
  const xyz = new Array(width * height * 3);
  for (let i = 0; i < width * height; i++) for (let c = 0; c < 3; c++) xyz[3 * i + c] = buf[4 * i + c];
  return xyz;
}
// Test hook: a glossy bake's h_k lookup as the emitted snippet does it (its own
// prtkitGlossyCosThetaPhi, prtkitGlossyTaps and prtkitGlossyH, reading the page's h texture) at
// each direction w of the normal's frame ([x, y, z] in prtkit's axes), for every term:
// returns values[k][i] = h_k(w_i), evaluated in the shader's float precision.
function glossyLookup(directions) {
  const D = directions.length, K = docs.glossy.h.image.height / docs.glossy.h.image.width;
  const dirs = new THREE.DataTexture(new Float32Array(directions.flatMap((w) => [...w, 0])), D, 1, THREE.RGBAFormat, THREE.FloatType);
  dirs.minFilter = dirs.magFilter = THREE.NearestFilter; // read by texelFetch only
  dirs.needsUpdate = true;
  const buf = renderFloats(`${docs.glossy.snippet}
      uniform sampler2D directions;
      void main() {
        ivec2 p = ivec2(gl_FragCoord.xy); // x: the direction, y: the term
        vec3 w = texelFetch(directions, ivec2(p.x, 0), 0).xyz;
        gl_FragColor = vec4(prtkitGlossyH(p.y, prtkitGlossyTaps(prtkitGlossyCosThetaPhi(w))), 0.0, 0.0, 1.0);
      }`,
  { directions: { value: dirs }, prtkitGlossyHTexture: { value: docs.glossy.h } }, D, K);
  dirs.dispose();
  return Array.from({ length: K }, (_, k) => Array.from({ length: D }, (_, i) => buf[4 * (k * D + i)]));
}

function updateUniforms() {
  if (SH_MODES.includes(state.mode)) { updateShUniforms(); return; }
  const common = prtkitUniforms(ibl, rotation());
  const materials = state.mode === 'model' ? model.materials : spheres.children.map((s) => s.material);
  for (const material of [skyMaterial, ...materials]) {
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
  for (const material of model.materials) {
    if (!material.userData.fromObj) continue; // glTF materials keep their own
    material.uniforms.roughness.value = state.r;
    material.uniforms.metalness.value = state.m;
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
  if (SH_MODES.includes(state.mode)) {
    await setupShMode();
    updateUniforms();
    return;
  }
  if (!ibl || ibl.frame !== state.frame) {
    const url = q.get('ibl');
    if (!url) { // nothing to show yet: say how to give it
      document.getElementById('source').textContent = 'drop a bake (ibl.json and its files) here, or give ?ibl=DIR/';
      return;
    }
    ibl = await loadPrtkitIbl(url, { frame: state.frame, urlOf: dropped.bake ? dropped.urlOf : undefined });
    document.getElementById('source').textContent = ibl.manifest.source.split('/').pop();
  }
  if (state.mode === 'model') await buildModel();
  else buildSpheres();
  if (state.sky === 'builtin') {
    // three's own skybox path with the loader's cube: it negates x itself (frame=three only).
    scene.background = ibl.background;
  } else {
    scene.add(sky);
  }
  scene.add(spheres);
  updateUniforms();
}

// --- files dropped on the page ---------------------------------------------------------------
// Each dropped file, and every file under a dropped folder, gets an object URL; the page then
// opens them as it opens URLs, in the mode they call for (the first of these that applies):
//   a .glb whose mesh holds prtkit.transfer extras → mode prt (with the dropped .sh.json and, for a
//     glossy bake, the dropped .glsl snippet);
//   any other .gltf/.glb or an .obj → mode model, lit by the bake dropped with it or already open
//     (a .gltf's .bin and textures dropped with it are found by name);
//   ibl.json (a prtkit.ibl manifest) and the files it names → the bake (mode grid, or the current
//     mode if it already shows a bake: sphere, sky, model);
//   a prtkit.normal-codes report (encode-normals) with the codes it names, the GLSL decoder and a
//     prtkit.sh document → mode normals;
//   a prtkit.shrm document (prefilter --shrm) with the EXR it names → mode shrm;
//   a prtkit.sh document (sh-project) → mode irradiance.
const IBL_MODES = ['grid', 'sphere', 'sky', 'model'];
const dropped = {
  urls: new Map(), // file name → object URL
  bake: false,
  urlOf: (name) => dropped.urls.get(name) ?? name,
  // glTF resources (buffers, images) by the name the .gltf gives them.
  manager: () => {
    if (!dropped.urls.size) return undefined;
    const manager = new THREE.LoadingManager();
    manager.setURLModifier((u) => dropped.urls.get(decodeURIComponent(u.split(/[?#]/)[0].split('/').pop())) ?? u);
    return manager;
  },
};
// What a drop holds, each found by its content (JSON by its `format`, a .glsl by the function it
// defines, a .glb by its prtkit.transfer extras), the first of a kind in the drop's order.
async function classifyDrop(files) {
  const ext = (f) => f.name.toLowerCase().split('.').pop();
  const text = new Map();
  for (const f of files) if (['json', 'glsl'].includes(ext(f))) text.set(f, await f.text());
  const json = (f) => { try { return JSON.parse(text.get(f)); } catch { return null; } };
  const byFormat = (format) => files.find((f) => ext(f) === 'json' && json(f)?.format === format);
  const glslWith = (name) => files.find((f) => ext(f) === 'glsl' && text.get(f).includes(name));
  const found = {
    manifest: byFormat('prtkit.ibl'), sh: byFormat('prtkit.sh'), shrm: byFormat('prtkit.shrm'), codesReport: byFormat('prtkit.normal-codes'),
    glossyGlsl: glslWith('prtkitGlossyRadiance'), decoder: glslWith('prtkit_decode_normal'), prt: null, model: null, json,
  };
  for (const f of files.filter((f) => ['glb', 'gltf', 'obj'].includes(ext(f)))) {
    let isPrt = false;
    if (ext(f) === 'glb') {
      const gltf = await new GLTFLoader().loadAsync(dropped.urls.get(f.name)).catch(() => null);
      gltf?.scene.traverse((o) => { if (o.isMesh && o.userData['prtkit.transfer']) isPrt = true; });
    }
    if (isPrt) found.prt ??= f; else found.model ??= f;
  }
  return found;
}
// A dropped file named by a document (its last path component), or a clear error.
function droppedBeside(doc, path, what) {
  const name = path.split('/').pop();
  const u = dropped.urls.get(name);
  if (!u) throw new Error(`dropped ${doc.name}: ${what} ${name} was not dropped with it`);
  return u;
}
// The query an encode-normals drop stands for: its codes (the file the report names), the report,
// the GLSL decoder and a prtkit.sh document; the table is taken as lat-long 2:1 (count = 2H²).
function normalsQuery(found) {
  const report = found.json(found.codesReport), H = Math.round(Math.sqrt(report.count / 2));
  if (2 * H * H !== report.count) throw new Error(`dropped ${found.codesReport.name}: ${report.count} codes are not a 2:1 lat-long table (2H² codes); open it by URL with size=WxH`);
  if (!found.decoder) throw new Error(`dropped ${found.codesReport.name}: no GLSL decoder (encode-normals --emit-decoder glsl) dropped with it`);
  if (!found.sh) throw new Error(`dropped ${found.codesReport.name}: no prtkit.sh document (sh-project) to light the normals dropped with it`);
  return { codes: droppedBeside(found.codesReport, report.codes ?? '', 'the codes'), report: dropped.urls.get(found.codesReport.name),
    decoder: dropped.urls.get(found.decoder.name), size: `${2 * H}x${H}` };
}
async function openFiles(files) {
  for (const u of dropped.urls.values()) URL.revokeObjectURL(u);
  dropped.urls = new Map(files.map((f) => [f.name, URL.createObjectURL(f)]));
  const found = await classifyDrop(files);
  const { manifest, sh, shrm, codesReport, prt } = found;
  if (!manifest && !sh && !shrm && !codesReport && !prt && !found.model) {
    throw new Error(`dropped ${files.map((f) => f.name).join(', ')}: no ibl.json, prtkit.sh, prtkit.shrm or prtkit.normal-codes document, .glb, .gltf or .obj among them`);
  }
  if (found.model && !prt && !manifest && !ibl) {
    throw new Error(`dropped ${found.model.name}: a model is lit by an ibl bake; drop it with the bake's folder or files, or open a bake first`);
  }
  for (const k of ['sh', 'glb', 'glsl', 'model', 'type', 'shrm', 'codes', 'report', 'decoder', 'size']) q.delete(k);
  for (const k of Object.keys(docs)) delete docs[k];
  model.key = '';
  if (manifest) {
    dropped.urls.set('ibl.json', dropped.urls.get(manifest.name)); // the loader asks for ibl.json
    dropped.bake = true;
    ibl = null;
    q.set('ibl', 'dropped/');
  }
  if (sh) q.set('sh', dropped.urls.get(sh.name));
  if (prt) {
    state.mode = 'prt';
    q.set('glb', dropped.urls.get(prt.name));
    if (found.glossyGlsl) q.set('glsl', dropped.urls.get(found.glossyGlsl.name));
  } else if (found.model) {
    state.mode = 'model';
    q.set('model', dropped.urls.get(found.model.name));
    q.set('type', found.model.name.toLowerCase().split('.').pop());
  } else if (manifest) {
    if (!IBL_MODES.includes(state.mode) || state.mode === 'model') state.mode = 'grid';
  } else if (codesReport) {
    state.mode = 'normals';
    for (const [k, v] of Object.entries(normalsQuery(found))) q.set(k, v);
  } else if (shrm) {
    state.mode = 'shrm';
    droppedBeside(shrm, found.json(shrm).shrm_file ?? '', 'its EXR');
    q.set('shrm', dropped.urls.get(shrm.name));
  } else if (sh) state.mode = 'irradiance';
  if (!q.has('eye')) placeCamera();
  if (!test) document.getElementById('mode').value = state.mode;
  await setup();
  draw();
  return true;
}
// A drop's items, taken while the event is dispatched (a DataTransfer is emptied after it): a
// folder as its FileSystemDirectoryEntry (webkitGetAsEntry), a file as its File.
function dropEntries(dataTransfer) {
  const items = [...(dataTransfer?.items ?? [])].filter((i) => i.kind === 'file');
  if (!items.length) return [...(dataTransfer?.files ?? [])];
  return items.map((i) => {
    const entry = i.webkitGetAsEntry?.();
    return entry?.isDirectory ? entry : i.getAsFile();
  }).filter(Boolean);
}
// Every file under a dropped folder, subfolders included, each folder's entries in name order
// (readEntries returns them a batch at a time, in no set order, until an empty batch).
async function filesUnder(entry) {
  if (entry.isFile) return [await new Promise((ok, fail) => entry.file(ok, fail))];
  const reader = entry.createReader(), entries = [];
  for (let batch; (batch = await new Promise((ok, fail) => reader.readEntries(ok, fail))).length;) entries.push(...batch);
  entries.sort((a, b) => (a.name < b.name ? -1 : a.name > b.name ? 1 : 0));
  const files = [];
  for (const e of entries) files.push(...(await filesUnder(e)));
  return files;
}
addEventListener('dragover', (e) => e.preventDefault());
addEventListener('drop', (e) => {
  e.preventDefault();
  const entries = dropEntries(e.dataTransfer);
  if (!entries.length) return;
  window.prtkit.ready = Promise.all(entries.map((x) => (x.isDirectory ? filesUnder(x) : [x])))
    .then((lists) => openFiles(lists.flat()))
    .catch((err) => { report(err.stack ?? err); return false; });
});

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
  return readFrame(gl, W, H);
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
  decodedNormals,
  glossyLookup,
  rotateShZ,
  sh: () => docs.sh?.coefficients,
  state: () => ({ ...state, ibl: q.get('ibl'), sh: q.get('sh'), model: q.get('model'), glb: q.get('glb'), dropped: [...dropped.urls.keys()] }),
  // ms per call of the per-cluster half of compressed relighting (the CPU's share of a frame).
  cpcaProjectMs: (calls = 20) => {
    const t0 = performance.now();
    for (let i = 0; i < calls; i++) projectCpcaLighting(docs.cpca, rotateShZ(docs.sh.coefficients, i * 0.01));
    return (performance.now() - t0) / calls;
  },
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
  for (const id of ['r', 'm', 'exposure', 'rotate']) el(id).oninput = (e) => { state[id] = Number(e.target.value); if (ibl || SH_MODES.includes(state.mode)) updateUniforms(); };
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
