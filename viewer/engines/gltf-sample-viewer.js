// prtkit's `ibl` bake drawn by the Khronos glTF Sample Viewer's renderer (npm
// @khronosgroup/gltf-viewer 1.1.0, ES module and its libktx served from viewer/node_modules; no CDN).
//
// The package's API takes an environment only as an HDR panorama (ResourceLoader.loadEnvironment,
// which prefilters it itself). What it draws from is `state.environment`: the object
// loadEnvironment returns, a glTF-like holder of WebGL textures (images of mimeType
// "image/texture" whose `image` is the GL texture) with `specularEnvMap`, `diffuseEnvMap`, `lut`,
// `sheenEnvMap`, `sheenLUT` (texture infos), `mipCount` and `iblIntensityScale`. This page fills
// that object with prtkit's files instead, each read by the Sample Viewer's own KTX2 reader
// (libktx's glUpload, through ResourceLoader.initKtxLib): specular.ktx2 (cube, all mips) as the
// GGX cube, irradiance.ktx2 (E/π per texel, what its Lambertian cube holds) as the diffuse cube,
// dfg.ktx2 (RG = scale, bias at uv = (n·v, roughness), what its u_GGXLUT holds) as the LUT.
//
// Query: ibl=URL/ (the bake; default variant scale-bias), mode=sky|sphere (sphere: a unit sphere
// of base colour base=R,G,B, metalness m, roughness r in front of the sky), rot=DEG (renderingParameters.
// environmentRotation; the Sample Viewer's default is 90), env=bake|hdr (hdr: the Sample Viewer's
// own loadEnvironment(src) prefilter of the HDR panorama src=URL instead of the bake: slow on a CPU
// rasterizer; it also asks for assets/images/lut_sheen_E.png, which the npm package does not ship:
// a 404), eye, target (glTF frame), fov (vertical, degrees), res W×H.
// Exposes window.prtkit = { ready, pixels(), errors } as the three.js viewer does (test/run.mjs).
// The Sample Viewer writes pow(c, 1/2.2), not the sRGB curve (its tonemapping.glsl linearTosRGB).
import { GltfView, ResourceLoader } from '../node_modules/@khronosgroup/gltf-viewer/dist/gltf-viewer.module.js';
import { exposeEnginePage } from '../src/readback.js';

const LIB = '../node_modules/@khronosgroup/gltf-viewer/dist/libs/';
const q = new URLSearchParams(location.search);
const num3 = (s, d) => (s ?? d).split(',').map(Number);
const [W, H] = (q.get('res') ?? '192x192').split('x').map(Number);
const errors = [];
const canvas = document.getElementById('c');
canvas.width = W; canvas.height = H;
canvas.style.width = `${W}px`; canvas.style.height = `${H}px`;
const gl = canvas.getContext('webgl2', { preserveDrawingBuffer: true, antialias: false });
const view = new GltfView(gl);
const state = view.createState();

// A GLB of one scene: empty, or (mode=sphere) a unit sphere of one metal/rough material. renderFrame
// draws nothing, not even the environment, without a loaded glTF scene (GltfView.renderFrame
// returns when state.gltf is undefined).
function sceneGlb(sphere) {
  const gltf = { asset: { version: '2.0' }, scene: 0, scenes: [{ nodes: sphere ? [0] : [] }] };
  let bin = new Uint8Array(0);
  if (sphere) {
    const rings = 48, segs = 96, pos = [], idx = [];
    for (let i = 0; i <= rings; i++) {
      const t = (Math.PI * i) / rings;
      for (let j = 0; j <= segs; j++) {
        const ph = (2 * Math.PI * j) / segs;
        pos.push(Math.sin(t) * Math.cos(ph), Math.cos(t), -Math.sin(t) * Math.sin(ph));
      }
    }
    for (let i = 0; i < rings; i++) {
      for (let j = 0; j < segs; j++) {
        const a = i * (segs + 1) + j, b = a + segs + 1; // counter-clockwise seen from outside
        idx.push(a, b, a + 1, a + 1, b, b + 1);
      }
    }
    const P = new Float32Array(pos), I = new Uint32Array(idx);
    bin = new Uint8Array(P.byteLength + I.byteLength);
    bin.set(new Uint8Array(P.buffer), 0);
    bin.set(new Uint8Array(I.buffer), P.byteLength);
    Object.assign(gltf, {
      nodes: [{ mesh: 0 }],
      meshes: [{ primitives: [{ attributes: { POSITION: 0, NORMAL: 0 }, indices: 1, material: 0 }] }],
      materials: [{ pbrMetallicRoughness: { baseColorFactor: [...sphere.base, 1], metallicFactor: sphere.m, roughnessFactor: sphere.r } }],
      buffers: [{ byteLength: bin.byteLength }],
      bufferViews: [{ buffer: 0, byteOffset: 0, byteLength: P.byteLength, target: 34962 },
        { buffer: 0, byteOffset: P.byteLength, byteLength: I.byteLength, target: 34963 }],
      accessors: [{ bufferView: 0, componentType: 5126, count: P.length / 3, type: 'VEC3', min: [-1, -1, -1], max: [1, 1, 1] },
        { bufferView: 1, componentType: 5125, count: I.length, type: 'SCALAR' }],
    });
  }
  let json = JSON.stringify(gltf);
  while (json.length % 4) json += ' ';
  const body = new TextEncoder().encode(json);
  const binChunk = bin.byteLength ? 8 + bin.byteLength : 0;
  const glb = new DataView(new ArrayBuffer(12 + 8 + body.length + binChunk));
  glb.setUint32(0, 0x46546c67, true); // "glTF"
  glb.setUint32(4, 2, true);
  glb.setUint32(8, glb.byteLength, true);
  glb.setUint32(12, body.length, true);
  glb.setUint32(16, 0x4e4f534a, true); // "JSON"
  new Uint8Array(glb.buffer, 20).set(body);
  if (binChunk) {
    glb.setUint32(20 + body.length, bin.byteLength, true);
    glb.setUint32(24 + body.length, 0x004e4942, true); // "BIN\0"
    new Uint8Array(glb.buffer, 28 + body.length).set(bin);
  }
  return glb.buffer;
}

// One of prtkit's KTX2 files as a WebGL texture, uploaded by the Sample Viewer's libktx reader.
async function ktxTexture(url, target, mipmapped) {
  const tex = await view.ktxDecoder.loadKtxFromUri(url);
  if (!tex) throw new Error(`${url}: the Sample Viewer's KTX2 reader returned nothing`);
  gl.bindTexture(target, tex);
  // The filters loadEnvironment's own cubes get (ibl_sampler.js createCubemapTexture).
  gl.texParameteri(target, gl.TEXTURE_MIN_FILTER, mipmapped ? gl.LINEAR_MIPMAP_LINEAR : gl.LINEAR);
  gl.texParameteri(target, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
  gl.texParameteri(target, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
  gl.texParameteri(target, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
  gl.bindTexture(target, null);
  return tex;
}

// The object ResourceLoader.loadEnvironment returns, with prtkit's textures in it.
function environmentOf({ specular, irradiance, dfg, levels }) {
  const images = [], textures = [];
  const info = (glTexture, type) => {
    images.push({ mimeType: 'image/texture', image: glTexture, type });
    textures.push({ source: images.length - 1, type, glTexture, initialized: true });
    return { index: textures.length - 1, texCoord: 0, linear: true, generateMips: false };
  };
  const specularEnvMap = info(specular, gl.TEXTURE_CUBE_MAP);
  const diffuseEnvMap = info(irradiance, gl.TEXTURE_CUBE_MAP);
  const lut = info(dfg, gl.TEXTURE_2D);
  return {
    images, textures, samplers: [],
    specularEnvMap, diffuseEnvMap, lut,
    // No sheen in prtkit's bake; the renderer binds these slots for every material, so they point
    // at the GGX cube and table (read only by KHR_materials_sheen materials).
    sheenEnvMap: specularEnvMap, sheenLUT: lut, sheenELUT: lut,
    mipCount: levels, // its shaders take lod = roughness · (mipCount − 1): ibl's linear map
    iblIntensityScale: 1,
  };
}

async function setup() {
  const loader = new ResourceLoader(view, LIB);
  loader.initKtxLib();
  const sphere = q.get('mode') === 'sphere'
    ? { base: num3(q.get('base'), '1,1,1'), m: Number(q.get('m') ?? 1), r: Number(q.get('r') ?? 0.3) } : null;
  state.gltf = await loader.loadGltf(sceneGlb(sphere));
  const p = state.renderingParameters;
  p.toneMap = 'None (Linear mapping, clamped at 1.0)'; // GltfState.ToneMaps.NONE
  p.blurEnvironmentMap = false; // else the background is level 0.6 · (mipCount − 1)
  p.renderEnvironmentMap = true;
  p.exposure = 1;
  p.iblIntensity = 1;
  p.usePunctual = false;
  p.clearColor = [0, 0, 0, 255];
  p.environmentRotation = Number(q.get('rot') ?? 0);

  if (q.get('env') === 'hdr') {
    state.environment = await loader.loadEnvironment(q.get('src'));
  } else {
    const ibl = q.get('ibl');
    const manifest = await (await fetch(`${ibl}ibl.json`)).json();
    if (manifest.specular.roughness_map !== 'linear') throw new Error(`${ibl}ibl.json: roughness_map ${manifest.specular.roughness_map}; the Sample Viewer takes lod = r · (mipCount − 1): bake with the default --roughness-map linear`);
    if (manifest.dfg.variant !== 'scale-bias') throw new Error(`${ibl}ibl.json: dfg.variant ${manifest.dfg.variant}; the Sample Viewer reads (scale, bias): bake without --dfg multiscatter`);
    state.environment = environmentOf({
      specular: await ktxTexture(`${ibl}${manifest.specular.file}`, gl.TEXTURE_CUBE_MAP, true),
      irradiance: await ktxTexture(`${ibl}${manifest.irradiance.file}`, gl.TEXTURE_CUBE_MAP, false),
      dfg: await ktxTexture(`${ibl}${manifest.dfg.file}`, gl.TEXTURE_2D, false),
      levels: manifest.specular.levels.length,
    });
  }

  // The user camera: setRotation(yaw, pitch) (radians) and setPosition, its public calls. (Its
  // lookAt(from, to) stores gl-matrix's view matrix where the camera's world transform belongs.)
  const eye = num3(q.get('eye'), '0,0,4'), target = num3(q.get('target'), '0,0,0');
  const f = target.map((t, i) => t - eye[i]), n = Math.hypot(...f);
  const cam = state.userCamera;
  cam.setRotation(Math.atan2(-f[0], -f[2]), Math.asin(f[1] / n));
  cam.setPosition(eye);
  cam.setVerticalFoV((Number(q.get('fov') ?? 60) * Math.PI) / 180);
  cam.perspective.znear = 0.05;
  cam.perspective.zfar = 100;
  view.renderFrame(state, W, H);
  return true;
}

exposeEnginePage({
  errors,
  setup,
  draw: () => view.renderFrame(state, W, H),
  context: () => gl,
  width: W,
  height: H,
  gpu: () => 'Khronos glTF Sample Viewer (npm @khronosgroup/gltf-viewer)',
});
