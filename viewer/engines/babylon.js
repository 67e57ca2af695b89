// prtkit's `ibl --format dds` bake loaded the way a Babylon.js user loads a prefiltered cube:
// CubeTexture.CreateFromPrefilteredData(specular.dds), shown as the skybox and on a PBR sphere.
// Babylon from npm (@babylonjs/core, ES modules served from viewer/node_modules; no CDN).
// Query (all optional but ibl):
//   ibl=URL/           the bake folder (made with --format dds)
//   hand=left|right    scene.useRightHandedSystem false (Babylon's default) or true
//   flip=none|x|z|xz   the cube is looked up with those axes negated (CubeTexture reflection matrix)
//   mode=sky|sphere    the skybox alone, or a metallic PBR sphere of roughness r in front of it
//   r, eye, target, fov, res   roughness; camera in Babylon's world; vertical fov (degrees); W×H
// Exposes window.prtkit = { ready, pixels(), errors } as the three.js viewer does (test/run.mjs).
import { Engine } from '../node_modules/@babylonjs/core/Engines/engine.js';
import { Scene } from '../node_modules/@babylonjs/core/scene.js';
import { FreeCamera } from '../node_modules/@babylonjs/core/Cameras/freeCamera.js';
import { Matrix, Vector3 } from '../node_modules/@babylonjs/core/Maths/math.vector.js';
import { Color3 } from '../node_modules/@babylonjs/core/Maths/math.color.js';
import { CubeTexture } from '../node_modules/@babylonjs/core/Materials/Textures/cubeTexture.js';
import { PBRMaterial } from '../node_modules/@babylonjs/core/Materials/PBR/pbrMaterial.js';
import { CreateSphere } from '../node_modules/@babylonjs/core/Meshes/Builders/sphereBuilder.js';
import '../node_modules/@babylonjs/core/Materials/Textures/Loaders/ddsTextureLoader.js';
import '../node_modules/@babylonjs/core/Helpers/sceneHelpers.js';
import { exposeEnginePage } from '../src/readback.js';

const q = new URLSearchParams(location.search);
const vec = (s, d) => Vector3.FromArray((s ?? d).split(',').map(Number));
const [W, H] = (q.get('res') ?? '192x192').split('x').map(Number);
const errors = [];
const canvas = document.getElementById('c');
canvas.width = W; canvas.height = H;
canvas.style.width = `${W}px`; canvas.style.height = `${H}px`;

// Exact sRGB encoding (Babylon's default is pow(1/2.2)); no antialiasing, no tone mapping.
const engine = new Engine(canvas, false, { preserveDrawingBuffer: true, useExactSrgbConversions: true, adaptToDeviceRatio: false });
const scene = new Scene(engine);
scene.useRightHandedSystem = q.get('hand') === 'right';
scene.clearColor.set(0, 0, 0, 1);
scene.imageProcessingConfiguration.toneMappingEnabled = false;
scene.imageProcessingConfiguration.exposure = 2 ** Number(q.get('exposure') ?? 0);

const camera = new FreeCamera('camera', vec(q.get('eye'), '0,0,-4'), scene);
camera.setTarget(vec(q.get('target'), '0,0,0'));
camera.fov = (Number(q.get('fov') ?? 60) * Math.PI) / 180;
camera.minZ = 0.05;
camera.maxZ = 5000;

async function setup() {
  const ibl = q.get('ibl');
  const tex = CubeTexture.CreateFromPrefilteredData(`${ibl}specular.dds`, scene);
  tex.gammaSpace = false; // linear RGBA16F radiance
  const flip = q.get('flip') ?? 'none';
  if (flip !== 'none') tex.setReflectionTextureMatrix(Matrix.Scaling(flip.includes('x') ? -1 : 1, 1, flip.includes('z') ? -1 : 1));
  await new Promise((ok, fail) => {
    if (tex.isReady()) ok();
    tex.onLoadObservable.addOnce(() => ok());
    setTimeout(() => fail(new Error(`${ibl}specular.dds: not loaded after 20 s`)), 20000);
  });
  scene.environmentTexture = tex;
  scene.createDefaultSkybox(tex, true, 1000, 0);
  if (q.get('mode') === 'sphere') {
    const sphere = CreateSphere('sphere', { diameter: 2, segments: 64 }, scene);
    const m = new PBRMaterial('metal', scene);
    m.albedoColor = new Color3(...(q.get('base') ?? '1,1,1').split(',').map(Number));
    m.metallic = 1;
    m.roughness = Number(q.get('r') ?? 0.3);
    m.reflectionTexture = tex;
    sphere.material = m;
  }
  await scene.whenReadyAsync();
  scene.render();
  return true;
}

exposeEnginePage({
  errors,
  setup,
  draw: () => scene.render(),
  context: () => engine._gl,
  width: W,
  height: H,
  gpu: () => 'Babylon.js ' + Engine.Version,
});
