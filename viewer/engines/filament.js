// prtkit's `ibl` bake loaded the way a Filament web user builds an IndirectLight from raw faces
// (npm `filament`, its WebGL 2 / WASM build, served from viewer/node_modules; no CDN): the levels
// of specular.ktx2 (parsed with ktx-parse) go to Texture.setImageCube, six faces per level in the
// KTX2 order +X, −X, +Y, −Y, +Z, −Z; sh.json's coefficients to IndirectLight.irradianceSh(3, …);
// the cube is also the Skybox. Filament is right-handed, +Y up: the glTF frame ibl writes.
// Query: ibl=URL/ (the bake), turn=DEG (IndirectLight.rotation about +Y, which Filament applies to
// the skybox too; 0 by default), eye, target (glTF frame), fov (vertical, degrees), res W×H.
// Exposes window.prtkit = { ready, pixels(), errors } as the three.js viewer does (test/run.mjs).
import { read } from '../node_modules/ktx-parse/dist/index.mjs';
import { exposeEnginePage } from '../src/readback.js';

const q = new URLSearchParams(location.search);
const num3 = (s, d) => (s ?? d).split(',').map(Number);
const [W, H] = (q.get('res') ?? '192x192').split('x').map(Number);
const errors = [];
const canvas = document.getElementById('c');
canvas.width = W; canvas.height = H;
canvas.style.width = `${W}px`; canvas.style.height = `${H}px`;
let engine, renderer, swapChain, view, gl;

async function fetchBytes(url) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  return new Uint8Array(await r.arrayBuffer());
}

// specular.ktx2 (RGBA16F cube, full mip chain) as a Filament cubemap texture.
function cubeFromKtx2(bytes) {
  const ktx = read(bytes);
  if (ktx.faceCount !== 6 || ktx.vkFormat !== 97) throw new Error('specular.ktx2: expected an RGBA16F (VK_FORMAT_R16G16B16A16_SFLOAT) cube');
  const tex = Filament.Texture.Builder()
    .width(ktx.pixelWidth).height(ktx.pixelHeight).levels(ktx.levels.length)
    .sampler(Filament.Texture$Sampler.SAMPLER_CUBEMAP)
    .format(Filament.Texture$InternalFormat.RGBA16F)
    .build(engine);
  ktx.levels.forEach((level, k) => {
    const data = level.levelData; // six faces, one after the other, in Filament's face order
    tex.setImageCube(engine, k, Filament.PixelBuffer(data, Filament.PixelDataFormat.RGBA, Filament.PixelDataType.HALF));
  });
  return tex;
}

async function setup() {
  await new Promise((ok) => Filament.init([], ok));
  engine = Filament.Engine.create(canvas, { preserveDrawingBuffer: true });
  gl = canvas.getContext('webgl2');
  const scene = engine.createScene();
  swapChain = engine.createSwapChain();
  renderer = engine.createRenderer();
  const camera = engine.createCamera(Filament.EntityManager.get().create());
  view = engine.createView();
  view.setCamera(camera);
  view.setScene(scene);
  view.setViewport([0, 0, W, H]);
  view.setAntiAliasing(Filament.View$AntiAliasing.NONE);
  // Linear tone mapping: the output is the radiance, sRGB-encoded (Filament's colour-grading LUT).
  view.setColorGrading(Filament.ColorGrading.Builder().toneMapping(Filament.ColorGrading$ToneMapping.LINEAR).build(engine));
  renderer.setClearOptions({ clearColor: [0, 0, 0, 1], clear: true });
  camera.setProjectionFov(Number(q.get('fov') ?? 60), W / H, 0.05, 100, Filament.Camera$Fov.VERTICAL);
  camera.lookAt(num3(q.get('eye'), '0,0,4'), num3(q.get('target'), '0,0,0'), [0, 1, 0]);
  camera.setExposureDirect(1);

  const ibl = q.get('ibl');
  const tex = cubeFromKtx2(await fetchBytes(`${ibl}specular.ktx2`));
  const sh = JSON.parse(new TextDecoder().decode(await fetchBytes(`${ibl}sh.json`)));
  const turn = (Number(q.get('turn') ?? 0) * Math.PI) / 180, c = Math.cos(turn), s = Math.sin(turn);
  const light = Filament.IndirectLight.Builder()
    .reflections(tex)
    .irradianceSh(3, sh.coefficients.flat())
    .intensity(1)
    .rotation([c, 0, -s, 0, 1, 0, s, 0, c]) // column-major
    .build(engine);
  scene.setIndirectLight(light);
  scene.setSkybox(Filament.Skybox.Builder().environment(tex).build(engine));
  renderer.render(swapChain, view);
  return true;
}

exposeEnginePage({
  errors,
  setup,
  draw: () => renderer.render(swapChain, view),
  context: () => gl,
  width: W,
  height: H,
  gpu: () => 'Filament (npm filament)',
});
