// prtkit-loader.js — reads the output folder of `prtkit ibl` into three.js textures.
//
// Copy this file into your project; it needs `three` and `ktx-parse` (npm) and nothing else.
//
//   import { loadPrtkitIbl, PRTKIT_IBL_GLSL } from './prtkit-loader.js';
//   const ibl = await loadPrtkitIbl('/out/demo/ibl/');      // the folder holding ibl.json
//   scene.background = ibl.background;                      // three.js's own skybox path works as is
//   material.uniforms.envFromWorld.value = ibl.envFromWorld; // your shaders: see below
//
// What three.js can and cannot do with these files (three r187, checked in viewer/test/run.mjs):
//
// - specular.ktx2 and irradiance.ktx2 are RGBA16F (or RGBA32F) cube maps with a full mip chain.
//   three's KTX2Loader does NOT return a cube for them: for uncompressed formats it builds a 2-D
//   DataTexture of level 0's first face (createRawTexture ignores faceCount), which samples black
//   as a samplerCube. So this module parses the container with ktx-parse and builds a
//   THREE.CompressedCubeTexture by hand: six faces, every mip level, in the file's face order
//   +X, −X, +Y, −Y, +Z, −Z, uploaded as stored (flipY false). three uploads a CompressedTexture
//   whose format is RGBAFormat with texStorage2D + texSubImage2D, so half floats go to the GPU
//   unchanged and RGBA16F is linearly filterable in WebGL 2 (RGBA32F needs
//   OES_texture_float_linear). The packed formats (ibl --format b10g11r11 / e5b9g9r9) are not
//   supported here: bake with the default rgba16f.
// - dfg.ktx2 is a plain 2-D RG16F texture: three's KTX2Loader reads it correctly (a DataTexture);
//   only its filters must be set to linear (the loader defaults uncompressed data to nearest).
//   `loadPrtkitIbl` uses KTX2Loader for it when you pass `{ ktx2Loader }`, and ktx-parse otherwise
//   (same bytes either way).
//
// Frames — which way the x axis goes:
//
// - The cube files are written in the GL/Vulkan/KTX2 cube convention: sampling them with the raw
//   direction d of the manifest's output frame (glTF: +Y up) returns L(d), exactly what
//   prtkit's own `render` shows, and what raw WebGL/GL/Vulkan/WebGPU code does with texture(cube, d).
// - three.js's cube convention is the mirror image of that: its background and envMap shaders
//   sample every CubeTexture that is not a render target at (−x, y, z) (WebGLBackground.js and
//   WebGLMaterials.js premultiply diag(−1, 1, 1); PMREMGenerator's flipEnvMap = −1). Its
//   equirectangular mapping agrees with its cube convention, not with prtkit's lat-long one:
//   three's equirectUv puts column u at (−cos 2πu, ·, −sin 2πu) where prtkit's glTF frame puts
//   it at (+cos 2πu, ·, −sin 2πu). The same source map therefore appears in three.js mirrored in
//   x relative to prtkit's bake, however it is loaded.
// - So: three's built-in paths (scene.background, material.envMap) need no fix — they already
//   negate x. A ShaderMaterial that samples the cube itself must negate x as three does
//   (`envFromWorld` below = diag(−1, 1, 1), times any rotation you add), or the lighting will be
//   the mirror image of three's skybox and of three's own view of the source map.
// - Raw WebGL/GL/Vulkan/WebGPU with prtkit's frame: sample with the world direction unchanged.
//   Pass `{ frame: 'gl' }` to get envFromWorld = identity (the viewer's ?frame=gl); three's
//   built-in paths cannot be used then (they always negate x).
// - A bake made with `ibl --up z` is in prtkit's +Z-up frame: envFromWorld then also turns
//   three's +Y-up world into it. three's built-in paths only handle --up y (the default).

import * as THREE from 'three';
import { read } from 'ktx-parse';

// VkFormat values prtkit writes.
const VK_R16G16_SFLOAT = 83;
const VK_R16G16B16A16_SFLOAT = 97;
const VK_R32G32_SFLOAT = 103;
const VK_R32G32B32A32_SFLOAT = 109;

const FORMATS = {
  [VK_R16G16B16A16_SFLOAT]: { format: THREE.RGBAFormat, type: THREE.HalfFloatType, array: Uint16Array },
  [VK_R32G32B32A32_SFLOAT]: { format: THREE.RGBAFormat, type: THREE.FloatType, array: Float32Array },
  [VK_R16G16_SFLOAT]: { format: THREE.RGFormat, type: THREE.HalfFloatType, array: Uint16Array },
  [VK_R32G32_SFLOAT]: { format: THREE.RGFormat, type: THREE.FloatType, array: Float32Array },
};

/** diag(−1, 1, 1): three.js's cube convention relative to GL/Vulkan's (see the header). */
export const THREE_FROM_GL = new THREE.Matrix3().set(-1, 0, 0, 0, 1, 0, 0, 0, 1);

/** prtkit's +Z-up frame from glTF's +Y-up frame: the transpose of `ibl --up y`'s U. */
const PRTKIT_FROM_GLTF = new THREE.Matrix3().set(1, 0, 0, 0, 0, -1, 0, 1, 0);

async function fetchBytes(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return new Uint8Array(await response.arrayBuffer());
}

function typedLevel(kind, levelData) {
  const bytes = levelData.slice(); // own, aligned copy
  return new kind.array(bytes.buffer, 0, bytes.byteLength / kind.array.BYTES_PER_ELEMENT);
}

/**
 * A prtkit KTX2 cube map (every mip level) as a THREE.CompressedCubeTexture, faces as stored.
 * @param {Uint8Array} bytes the .ktx2 file
 */
export function cubeFromKtx2(bytes, name = 'cube') {
  const ktx = read(bytes);
  const kind = FORMATS[ktx.vkFormat];
  if (ktx.faceCount !== 6) throw new Error(`${name}: ${ktx.faceCount} face(s), not a cube map`);
  if (!kind || kind.format !== THREE.RGBAFormat) {
    throw new Error(`${name}: vkFormat ${ktx.vkFormat} not supported by this loader (bake with --format rgba16f or rgba32f)`);
  }
  if (ktx.supercompressionScheme !== 0) throw new Error(`${name}: supercompressed KTX2 not supported`);
  const faces = [0, 1, 2, 3, 4, 5].map(() => ({ mipmaps: [], width: ktx.pixelWidth, height: ktx.pixelHeight }));
  ktx.levels.forEach((level, p) => {
    const size = Math.max(1, ktx.pixelWidth >> p);
    const data = typedLevel(kind, level.levelData);
    const faceLength = data.length / 6; // KTX2 stores each level's faces one after the other
    for (let f = 0; f < 6; f++) {
      faces[f].mipmaps.push({ data: data.subarray(f * faceLength, (f + 1) * faceLength), width: size, height: size });
    }
  });
  const texture = new THREE.CompressedCubeTexture(faces, kind.format, kind.type);
  texture.minFilter = ktx.levels.length > 1 ? THREE.LinearMipmapLinearFilter : THREE.LinearFilter;
  texture.magFilter = THREE.LinearFilter;
  texture.generateMipmaps = false;
  texture.colorSpace = THREE.LinearSRGBColorSpace; // linear radiance
  texture.flipY = false;
  texture.needsUpdate = true;
  texture.userData.levels = ktx.levels.length;
  texture.userData.size = ktx.pixelWidth;
  return texture;
}

/** A prtkit 2-D KTX2 table (the DFG) as a linearly filtered THREE.DataTexture, row 0 at v = 0. */
export function tableFromKtx2(bytes, name = 'table') {
  const ktx = read(bytes);
  const kind = FORMATS[ktx.vkFormat];
  if (ktx.faceCount !== 1 || !kind) throw new Error(`${name}: not a 2-D RG/RGBA float table`);
  const texture = new THREE.DataTexture(typedLevel(kind, ktx.levels[0].levelData), ktx.pixelWidth, ktx.pixelHeight, kind.format, kind.type);
  return finishTable(texture);
}

function finishTable(texture) {
  texture.minFilter = THREE.LinearFilter;
  texture.magFilter = THREE.LinearFilter;
  texture.wrapS = texture.wrapT = THREE.ClampToEdgeWrapping;
  texture.generateMipmaps = false;
  texture.flipY = false;
  texture.colorSpace = THREE.NoColorSpace;
  texture.needsUpdate = true;
  return texture;
}

/**
 * The lod of roughness r in the specular chain: piecewise linear through the manifest's levels
 * (`specular.levels[k].roughness`), which is what prtkit's render does between two levels. With
 * the default linear map this is r·(L − 1); with `--roughness-map filament` it is not.
 */
export function lodOfRoughness(levels, r) {
  const rs = levels.map((l) => l.roughness);
  if (r <= rs[0]) return 0;
  for (let k = 1; k < rs.length; k++) {
    if (r <= rs[k]) return k - 1 + (r - rs[k - 1]) / (rs[k] - rs[k - 1]);
  }
  return rs.length - 1;
}

/**
 * The lookup direction of prtkit's files from a three.js world direction, as a Matrix3:
 * envFromWorld · d_world is what to pass to textureCube / the SH polynomial.
 * @param {object} manifest ibl.json
 * @param {'three'|'gl'} frame 'three': agree with three's skybox/envMap and its equirect view of
 *   the source map (x negated); 'gl': the raw world direction, prtkit's and Vulkan/GL's view.
 * @param {number} rotateY extra environment turn about +Y, radians (counter-clockwise from above)
 */
export function envFromWorld(manifest, frame = 'three', rotateY = 0) {
  const m = new THREE.Matrix3();
  if (manifest.frame.up === 'z') m.copy(PRTKIT_FROM_GLTF);
  if (frame === 'three') m.multiply(THREE_FROM_GL);
  else if (frame !== 'gl') throw new Error(`frame ${frame}: 'three' or 'gl'`);
  // Turning the environment by θ = looking it up at R_y(−θ) d.
  const c = Math.cos(rotateY), s = Math.sin(rotateY);
  m.multiply(new THREE.Matrix3().set(c, 0, -s, 0, 1, 0, s, 0, c));
  return m;
}

/**
 * Reads DIR/ibl.json and the files it names.
 * @param {string} dir URL of the folder (trailing slash optional)
 * @param {{frame?: 'three'|'gl', ktx2Loader?: object}} options
 * @returns {Promise<{manifest, specular, background, irradiance, dfg, sh, envFromWorld, lodOfRoughness}>}
 *   specular: the whole chain (for your split-sum shader); background: level 0 alone, for
 *   scene.background
 */
export async function loadPrtkitIbl(dir, options = {}) {
  const base = dir.endsWith('/') ? dir : dir + '/';
  const manifest = await (await fetch(base + 'ibl.json')).json();
  if (manifest.format !== 'prtkit.ibl' || manifest.version !== 1) {
    throw new Error(`${base}ibl.json: not a prtkit.ibl version 1 manifest`);
  }
  if (manifest.specular.container !== 'ktx2') throw new Error('this loader reads KTX2 bakes (ibl --container ktx2)');
  const [spec, irr, shDoc] = await Promise.all([
    fetchBytes(base + manifest.specular.file),
    fetchBytes(base + manifest.irradiance.file),
    fetch(base + manifest.sh.file).then((r) => r.json()),
  ]);
  const specular = cubeFromKtx2(spec, manifest.specular.file);
  if (specular.userData.levels !== manifest.specular.levels.length) {
    throw new Error(`${manifest.specular.file}: ${specular.userData.levels} levels, the manifest lists ${manifest.specular.levels.length}`);
  }
  // three's scene.background samples a CubeTexture with implicit derivatives (textureCube): where
  // the view minifies the sky it would blend in the rougher levels of the chain. Give it level 0
  // alone (the same typed arrays, no copy).
  const background = new THREE.CompressedCubeTexture(
    specular.image.map((face) => ({ mipmaps: face.mipmaps.slice(0, 1), width: face.width, height: face.height })),
    specular.format, specular.type);
  background.minFilter = background.magFilter = THREE.LinearFilter;
  background.generateMipmaps = false;
  background.colorSpace = THREE.LinearSRGBColorSpace;
  background.needsUpdate = true;
  const irradiance = cubeFromKtx2(irr, manifest.irradiance.file);
  let dfg;
  if (options.ktx2Loader) {
    // three's own loader handles this one (a 2-D RG16F table); only the filters need changing.
    dfg = finishTable(await options.ktx2Loader.loadAsync(base + manifest.dfg.file));
  } else {
    dfg = tableFromKtx2(await fetchBytes(base + manifest.dfg.file), manifest.dfg.file);
  }
  // (A, B) in .rg: 'multiscatter' stores (B, A + B); the shader below wants (A, B).
  const dfgSwizzle = manifest.dfg.variant === 'multiscatter' ? 1 : 0;
  const sh = shDoc.coefficients.map((c) => new THREE.Vector3(c[0], c[1], c[2]));
  const frame = options.frame ?? 'three';
  return {
    manifest,
    specular,
    background,
    irradiance,
    dfg,
    dfgSwizzle,
    sh,
    frame,
    maxLod: manifest.specular.levels.length - 1,
    envFromWorld: (rotateY = 0) => envFromWorld(manifest, frame, rotateY),
    lodOfRoughness: (r) => lodOfRoughness(manifest.specular.levels, r),
  };
}

/**
 * GLSL (three.js ShaderMaterial, WebGL 2) of the split sum prtkit's `render --shading ibl` uses:
 *   specular = prefiltered(R', r) · (F0·A + B),  diffuse = (1 − m) c · E/π · (1 − (0.04·A + B)),
 * R' the dominant direction (Frostbite), E/π from the irradiance cube or the SH polynomial of
 * sh.json. Directions are world directions; `envFromWorld` takes them to the files' frame.
 */
export const PRTKIT_IBL_GLSL = /* glsl */ `
uniform samplerCube prtkitSpecular;
uniform samplerCube prtkitIrradiance;
uniform sampler2D prtkitDfg;
uniform mat3 envFromWorld;
uniform int prtkitDfgSwizzle;     // 0: (A, B); 1: multiscatter (B, A + B)
uniform int prtkitDiffuseFromSh;  // 0: irradiance cube; 1: sh.json polynomial
uniform vec3 prtkitSh[9];
uniform float prtkitLevelRoughness[16];
uniform int prtkitLevels;

float prtkitLod(float r) {
  if (r <= prtkitLevelRoughness[0]) return 0.0;
  for (int k = 1; k < 16; k++) {
    if (k >= prtkitLevels) break;
    if (r <= prtkitLevelRoughness[k]) {
      return float(k - 1) + (r - prtkitLevelRoughness[k - 1]) / (prtkitLevelRoughness[k] - prtkitLevelRoughness[k - 1]);
    }
  }
  return float(prtkitLevels - 1);
}

vec3 prtkitShIrradiance(vec3 n) { // E(n)/pi, n in the files' frame
  float x = n.x, y = n.y, z = n.z;
  return prtkitSh[0] + prtkitSh[1] * y + prtkitSh[2] * z + prtkitSh[3] * x + prtkitSh[4] * (x * y)
       + prtkitSh[5] * (y * z) + prtkitSh[6] * (3.0 * z * z - 1.0) + prtkitSh[7] * (x * z) + prtkitSh[8] * (x * x - y * y);
}

// n, v: unit world normal and direction towards the eye. Returns linear radiance.
vec3 prtkitSplitSum(vec3 n, vec3 v, vec3 base, float metalness, float roughness) {
  float nv = clamp(dot(n, v), 1e-4, 1.0);
  vec2 t = texture(prtkitDfg, vec2(nv, roughness)).rg;
  vec2 ab = prtkitDfgSwizzle == 1 ? vec2(t.y - t.x, t.x) : t;
  float alpha = roughness * roughness;
  float s = (1.0 - alpha) * (sqrt(1.0 - alpha) + alpha);
  vec3 r = 2.0 * dot(n, v) * n - v;
  vec3 rd = n + s * (r - n);
  rd = length(rd) > 0.0 ? normalize(rd) : n;
  vec3 pre = textureLod(prtkitSpecular, envFromWorld * rd, prtkitLod(roughness)).rgb;
  vec3 ne = envFromWorld * n;
  vec3 irr = prtkitDiffuseFromSh == 1 ? prtkitShIrradiance(ne) : textureLod(prtkitIrradiance, ne, 0.0).rgb;
  vec3 f0 = mix(vec3(0.04), base, metalness);
  vec3 kd = (1.0 - metalness) * base;
  return pre * (f0 * ab.x + ab.y) + kd * irr * (1.0 - (0.04 * ab.x + ab.y));
}
`;

/** The uniforms PRTKIT_IBL_GLSL declares, filled from a loaded bake. */
export function prtkitUniforms(ibl, rotateY = 0) {
  const roughness = new Array(16).fill(1);
  ibl.manifest.specular.levels.forEach((l, k) => { roughness[k] = l.roughness; });
  return {
    prtkitSpecular: { value: ibl.specular },
    prtkitIrradiance: { value: ibl.irradiance },
    prtkitDfg: { value: ibl.dfg },
    envFromWorld: { value: ibl.envFromWorld(rotateY) },
    prtkitDfgSwizzle: { value: ibl.dfgSwizzle },
    prtkitDiffuseFromSh: { value: 0 },
    prtkitSh: { value: ibl.sh },
    prtkitLevelRoughness: { value: roughness },
    prtkitLevels: { value: ibl.manifest.specular.levels.length },
  };
}
