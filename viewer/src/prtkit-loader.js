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
// - specular.ktx2 and irradiance.ktx2 are cube maps with a full mip chain. three's KTX2Loader
//   does NOT return a cube for them: for uncompressed formats it builds a 2-D DataTexture of
//   level 0's first face (createRawTexture ignores faceCount), which samples black as a
//   samplerCube. So this module parses the container itself (ktx-parse for KTX2, `readDds` below
//   for DDS) and builds a THREE.CompressedCubeTexture by hand: six faces, every mip level, in the
//   file's face order +X, −X, +Y, −Y, +Z, −Z, uploaded as stored (flipY false). three uploads a
//   CompressedTexture whose format is RGBAFormat with texStorage2D + texSubImage2D, so half
//   floats go to the GPU unchanged and RGBA16F is linearly filterable in WebGL 2 (RGBA32F needs
//   OES_texture_float_linear).
// - Every `ibl --format` is read. rgba16f and rgba32f are uploaded as they are. The packed
//   formats, b10g11r11 (VK_FORMAT_B10G11R11_UFLOAT_PACK32 / DXGI R11G11B10_FLOAT) and e5b9g9r9
//   (VK_FORMAT_E5B9G9R9_UFLOAT_PACK32 / DXGI R9G9B9E5_SHAREDEXP), are decoded on the CPU into
//   RGBA16F. Why not upload them packed (WebGL 2 has R11F_G11F_B10F and RGB9_E5 with
//   UNSIGNED_INT_10F_11F_11F_REV / UNSIGNED_INT_5_9_9_9_REV, and three r187 maps
//   UnsignedInt101111Type / UnsignedInt5999Type to them)? three sends every CompressedTexture
//   whose format is not RGBAFormat through compressedTexSubImage2D (WebGLTextures.js), so a
//   packed RGBFormat mip chain would need a CubeTexture of six mipmapped DataTextures, a second
//   upload path for one format family. Decoding is the simpler route and it loses nothing: an
//   11- or 10-bit unsigned float has half's 5-bit exponent with its bias 15 and 6 or 5 mantissa
//   bits, so it becomes a half by a shift (denormals, infinity and NaN included); a shared-exponent
//   texel is m·2^(e − 24) with a 9-bit m and e ≤ 31, exactly a half too (2^−24 is half's
//   smallest denormal, 511·2^7 ≤ 65504). The GPU filters the decoded halves as it would filter
//   the packed texels it decodes itself; the cost is 8 bytes a texel in GPU memory instead of 4.
// - DDS (`ibl --container dds`): the DX10 extended header, one cube (miscFlag TEXTURECUBE),
//   stored face by face, each face with all its mips (KTX2 stores level by level, each level
//   with its six faces); `readDds` reorders it into KTX2's layout.
// - dfg.ktx2 is a plain 2-D RG16F texture: three's KTX2Loader reads it correctly (a DataTexture);
//   only its filters must be set to linear (the loader defaults uncompressed data to nearest).
//   `loadPrtkitIbl` uses KTX2Loader for it when you pass `{ ktx2Loader }`, and ktx-parse otherwise
//   (same bytes either way). three's DDSLoader reads neither prtkit's DDS cubes nor its table (it
//   knows the DX10 header only for a few compressed and 8-bit formats), so dfg.dds goes through
//   `readDds` too.
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

// The texel formats prtkit writes, by their VkFormat (KTX2) and DXGI_FORMAT (DDS) numbers.
// `packed`: 4-byte texels decoded into RGBA16F on the CPU (see the header).
const RGBA16F = { name: 'rgba16f', format: THREE.RGBAFormat, type: THREE.HalfFloatType, array: Uint16Array };
const RGBA32F = { name: 'rgba32f', format: THREE.RGBAFormat, type: THREE.FloatType, array: Float32Array };
const RG16F = { name: 'rg16f', format: THREE.RGFormat, type: THREE.HalfFloatType, array: Uint16Array };
const RG32F = { name: 'rg32f', format: THREE.RGFormat, type: THREE.FloatType, array: Float32Array };
const B10G11R11 = { name: 'b10g11r11', packed: decodeB10G11R11 };
const E5B9G9R9 = { name: 'e5b9g9r9', packed: decodeE5B9G9R9 };
const VK_FORMATS = { 97: RGBA16F, 109: RGBA32F, 83: RG16F, 103: RG32F, 122: B10G11R11, 123: E5B9G9R9 };
const DXGI_FORMATS = { 10: RGBA16F, 2: RGBA32F, 34: RG16F, 16: RG32F, 26: B10G11R11, 67: E5B9G9R9 };

// An unsigned float of 5 exponent bits (bias 15, as half's) and `mbits` mantissa bits, as the
// bits of the equal half: the same exponent field, the mantissa moved to half's 10 bits. Exact
// for every value, denormals (exponent 0), infinity and NaN (exponent 31) included.
const ufloatToHalf = (bits, mbits) => bits << (10 - mbits);

/**
 * B10G11R11_UFLOAT_PACK32 (= DXGI R11G11B10_FLOAT) texels to RGBA16F bits, alpha 1:
 * R in bits 0–10 and G in 11–21 (6-bit mantissa), B in 22–31 (5-bit mantissa).
 */
export function decodeB10G11R11(words) {
  const out = new Uint16Array(words.length * 4);
  for (let i = 0; i < words.length; i++) {
    const w = words[i];
    out[4 * i] = ufloatToHalf(w & 0x7ff, 6);
    out[4 * i + 1] = ufloatToHalf((w >>> 11) & 0x7ff, 6);
    out[4 * i + 2] = ufloatToHalf(w >>> 22, 5);
    out[4 * i + 3] = 0x3c00; // 1.0
  }
  return out;
}

/**
 * E5B9G9R9_UFLOAT_PACK32 (= DXGI R9G9B9E5_SHAREDEXP) texels to RGBA16F bits, alpha 1: R, G, B
 * the 9-bit mantissas in bits 0–8, 9–17, 18–26 (no implicit 1), e in bits 27–31, each channel
 * m·2^(e − 15 − 9) (the KHR data format spec's RGB9E5). Every such value is a half: written as
 * one directly (a normal half when m's leading 1 leaves an exponent ≥ 1, else a denormal).
 */
export function decodeE5B9G9R9(words) {
  const out = new Uint16Array(words.length * 4);
  const half = (m, e) => {
    if (m === 0) return 0;
    // m·2^(e − 24) = 1.f · 2^(e − 24 + k), k = the index of m's leading bit.
    const k = 31 - Math.clz32(m);
    const exponent = e - 24 + k + 15; // half's biased exponent
    if (exponent >= 1) return (exponent << 10) | ((m << (10 - k)) & 0x3ff); // ≤ 30: e ≤ 31, k ≤ 8
    return m << e; // a denormal half d·2^−24 with d = m·2^e < 2^(k + 1 + e) ≤ 2^10
  };
  for (let i = 0; i < words.length; i++) {
    const w = words[i], e = w >>> 27;
    out[4 * i] = half(w & 0x1ff, e);
    out[4 * i + 1] = half((w >>> 9) & 0x1ff, e);
    out[4 * i + 2] = half((w >>> 18) & 0x1ff, e);
    out[4 * i + 3] = 0x3c00;
  }
  return out;
}

/** diag(−1, 1, 1): three.js's cube convention relative to GL/Vulkan's (see the header). */
export const THREE_FROM_GL = new THREE.Matrix3().set(-1, 0, 0, 0, 1, 0, 0, 0, 1);

/** prtkit's +Z-up frame from glTF's +Y-up frame: the transpose of `ibl --up y`'s U. */
const PRTKIT_FROM_GLTF = new THREE.Matrix3().set(1, 0, 0, 0, 0, -1, 0, 1, 0);

async function fetchBytes(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return new Uint8Array(await response.arrayBuffer());
}

// The texels of one mip level (all its faces) as the typed array three uploads: the format's own
// array for float formats, RGBA16F bits for the packed ones.
function typedLevel(kind, levelData) {
  const bytes = levelData.slice(); // own, aligned copy
  if (kind.packed) return kind.packed(new Uint32Array(bytes.buffer, 0, bytes.byteLength / 4));
  return new kind.array(bytes.buffer, 0, bytes.byteLength / kind.array.BYTES_PER_ELEMENT);
}
// What three is given for a kind: packed formats arrive as RGBA16F.
const uploaded = (kind) => (kind.packed ? RGBA16F : kind);

/**
 * A KTX2 file as { kind, width, height, faceCount, levels: [Uint8Array] }, each level its faces
 * one after the other (KTX2's own layout).
 * @param {Uint8Array} bytes the .ktx2 file
 */
export function readKtx2(bytes, name = 'ktx2') {
  const ktx = read(bytes);
  const kind = VK_FORMATS[ktx.vkFormat];
  if (!kind) throw new Error(`${name}: vkFormat ${ktx.vkFormat} is not one prtkit writes (rgba16f, rgba32f, b10g11r11, e5b9g9r9, rg16f, rg32f)`);
  if (ktx.supercompressionScheme !== 0) throw new Error(`${name}: supercompressed KTX2 not supported`);
  if (ktx.layerCount > 1 || ktx.pixelDepth > 1) throw new Error(`${name}: arrays and 3-D textures not supported`);
  return { kind, width: ktx.pixelWidth, height: ktx.pixelHeight, faceCount: ktx.faceCount, levels: ktx.levels.map((l) => l.levelData) };
}

/**
 * A DDS file with the DX10 header (what `ibl --container dds` writes) as readKtx2 returns it.
 * DDS stores a cube face by face, each face with all its mips; this reorders it level by level.
 * Layout (Microsoft's "DDS_HEADER" and "DDS_HEADER_DXT10"): "DDS " magic, a 124-byte header
 * (height at byte 12, width at 16, mip count at 28, pixel format FourCC at 84), then, FourCC
 * "DX10", 20 bytes: dxgiFormat at 128, resourceDimension at 132 (3: 2-D), miscFlag at 136
 * (4: TEXTURECUBE), arraySize at 140; texels from byte 148.
 * @param {Uint8Array} bytes the .dds file
 */
export function readDds(bytes, name = 'dds') {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const u32 = (at) => view.getUint32(at, true);
  const fourCC = (at) => String.fromCharCode(bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]);
  if (bytes.byteLength < 148 || fourCC(0) !== 'DDS ' || u32(4) !== 124) throw new Error(`${name}: not a DDS file`);
  if (fourCC(84) !== 'DX10') throw new Error(`${name}: a DDS without the DX10 header (prtkit writes DX10 only)`);
  const kind = DXGI_FORMATS[u32(128)];
  if (!kind) throw new Error(`${name}: DXGI_FORMAT ${u32(128)} is not one prtkit writes`);
  if (u32(132) !== 3 || u32(140) !== 1) throw new Error(`${name}: not a single 2-D texture or cube (dimension ${u32(132)}, array size ${u32(140)})`);
  const height = u32(12), width = u32(16), levelCount = Math.max(1, u32(28));
  const faceCount = u32(136) & 4 ? 6 : 1;
  const texel = kind.packed ? 4 : kind.array.BYTES_PER_ELEMENT * (kind.format === THREE.RGBAFormat ? 4 : 2);
  const faceBytes = (p) => Math.max(1, width >> p) * Math.max(1, height >> p) * texel;
  const levels = [];
  for (let p = 0; p < levelCount; p++) levels.push(new Uint8Array(faceBytes(p) * faceCount));
  let at = 148;
  for (let f = 0; f < faceCount; f++) {
    for (let p = 0; p < levelCount; p++) {
      const n = faceBytes(p);
      if (at + n > bytes.byteLength) throw new Error(`${name}: truncated (face ${f}, level ${p})`);
      levels[p].set(bytes.subarray(at, at + n), f * n);
      at += n;
    }
  }
  return { kind, width, height, faceCount, levels };
}

// A file's texels by its container: 'ktx2' or 'dds' (the manifest's `container`).
function readTexture(container, bytes, name) {
  if (container === 'ktx2') return readKtx2(bytes, name);
  if (container === 'dds') return readDds(bytes, name);
  throw new Error(`${name}: container ${container} (ktx2 or dds)`);
}

/**
 * A prtkit cube map (every mip level) as a THREE.CompressedCubeTexture, faces as stored.
 * @param {{kind, width, height, faceCount, levels}} image from readKtx2 or readDds
 */
export function cubeFromImage(image, name = 'cube') {
  if (image.faceCount !== 6) throw new Error(`${name}: ${image.faceCount} face(s), not a cube map`);
  const kind = uploaded(image.kind);
  if (kind.format !== THREE.RGBAFormat) throw new Error(`${name}: a ${image.kind.name} cube (prtkit's cubes are RGBA or packed RGB)`);
  const faces = [0, 1, 2, 3, 4, 5].map(() => ({ mipmaps: [], width: image.width, height: image.height }));
  image.levels.forEach((levelData, p) => {
    const size = Math.max(1, image.width >> p);
    const data = typedLevel(image.kind, levelData);
    const faceLength = data.length / 6; // each level's faces one after the other
    for (let f = 0; f < 6; f++) {
      faces[f].mipmaps.push({ data: data.subarray(f * faceLength, (f + 1) * faceLength), width: size, height: size });
    }
  });
  const texture = new THREE.CompressedCubeTexture(faces, kind.format, kind.type);
  texture.minFilter = image.levels.length > 1 ? THREE.LinearMipmapLinearFilter : THREE.LinearFilter;
  texture.magFilter = THREE.LinearFilter;
  texture.generateMipmaps = false;
  texture.colorSpace = THREE.LinearSRGBColorSpace; // linear radiance
  texture.flipY = false;
  texture.needsUpdate = true;
  texture.userData.levels = image.levels.length;
  texture.userData.size = image.width;
  texture.userData.fileFormat = image.kind.name;
  return texture;
}

/** A prtkit KTX2 cube map (every mip level, any `ibl --format`) as a THREE.CompressedCubeTexture. */
export const cubeFromKtx2 = (bytes, name = 'cube') => cubeFromImage(readKtx2(bytes, name), name);
/** A prtkit DDS cube map (DX10 header, any `ibl --format`) as a THREE.CompressedCubeTexture. */
export const cubeFromDds = (bytes, name = 'cube') => cubeFromImage(readDds(bytes, name), name);

/** A prtkit 2-D table (the DFG) as a linearly filtered THREE.DataTexture, row 0 at v = 0. */
export function tableFromImage(image, name = 'table') {
  if (image.faceCount !== 1) throw new Error(`${name}: not a 2-D table`);
  const kind = uploaded(image.kind);
  const texture = new THREE.DataTexture(typedLevel(image.kind, image.levels[0]), image.width, image.height, kind.format, kind.type);
  return finishTable(texture);
}
export const tableFromKtx2 = (bytes, name = 'table') => tableFromImage(readKtx2(bytes, name), name);
export const tableFromDds = (bytes, name = 'table') => tableFromImage(readDds(bytes, name), name);

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
 * @param {{frame?: 'three'|'gl', ktx2Loader?: object, urlOf?: (name: string) => string}} options
 * @returns {Promise<{manifest, specular, background, irradiance, dfg, sh, envFromWorld, lodOfRoughness}>}
 *   specular: the whole chain (for your split-sum shader); background: level 0 alone, for
 *   scene.background
 */
export async function loadPrtkitIbl(dir, options = {}) {
  const base = dir.endsWith('/') ? dir : dir + '/';
  // Where each file is: DIR/NAME, or options.urlOf(NAME) (e.g. object URLs of dropped files).
  const at = options.urlOf ?? ((name) => base + name);
  const manifest = await (await fetch(at('ibl.json'))).json();
  if (manifest.format !== 'prtkit.ibl' || manifest.version !== 1) {
    throw new Error(`${base}ibl.json: not a prtkit.ibl version 1 manifest`);
  }
  const container = manifest.specular.container; // 'ktx2' or 'dds', the same for every file
  const [spec, irr, shDoc] = await Promise.all([
    fetchBytes(at(manifest.specular.file)),
    fetchBytes(at(manifest.irradiance.file)),
    fetch(at(manifest.sh.file)).then((r) => r.json()),
  ]);
  const specular = cubeFromImage(readTexture(container, spec, manifest.specular.file), manifest.specular.file);
  if (specular.userData.fileFormat !== manifest.specular.format) {
    throw new Error(`${manifest.specular.file}: ${specular.userData.fileFormat} texels, the manifest says ${manifest.specular.format}`);
  }
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
  const irradiance = cubeFromImage(readTexture(container, irr, manifest.irradiance.file), manifest.irradiance.file);
  let dfg;
  if (options.ktx2Loader && container === 'ktx2') {
    // three's own loader handles this one (a 2-D RG16F table); only the filters need changing.
    dfg = finishTable(await options.ktx2Loader.loadAsync(at(manifest.dfg.file)));
  } else {
    dfg = tableFromImage(readTexture(container, await fetchBytes(at(manifest.dfg.file)), manifest.dfg.file), manifest.dfg.file);
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
