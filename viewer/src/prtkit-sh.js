// prtkit-sh.js — prtkit's SH documents in three.js: `sh-project`'s prtkit.sh (irradiance),
// `prefilter --shrm`'s prtkit.shrm + EXR layers (SHRMs), `encode-normals`' codes.
//
// Frames. prtkit's documents are in prtkit's frame: right-handed, +Z up, θ from +Z, φ from +X
// towards +Y. The viewer's three.js world is +Y up and, like three's own skybox and its
// equirectangular view of the same source map (prtkit-loader.js's header), prtkit's world
// mirrored in x after the glTF axis change (prtkit +Z → +Y, +Y → −Z):
//   d_three = (−x, z, −y)  ⇔  d_prtkit = (−x_t, −z_t, y_t)            (frame=three, default)
// With frame=gl (raw GL/Vulkan sampling, no mirror): d_prtkit = (x_t, −z_t, y_t).
// Every shader here turns the three.js world direction into prtkit's frame with `prtkitFromWorld`
// first and evaluates the documents there, so a document is never rewritten.
//
// SH convention (every prtkit document): real orthonormal SH, index l(l+1)+m, no Condon–Shortley
// phase: Y_1,−1 ∝ y, Y_1,0 ∝ z, Y_1,1 ∝ x, Y_l,m ∝ P_l^m(cos θ) cos(mφ) and Y_l,−m ∝
// P_l^m(cos θ) sin(mφ) (m > 0) with the same positive factor.
import * as THREE from 'three';

/** d_prtkit = prtkitFromWorld(frame) · d_three (see the header). */
export function prtkitFromWorld(frame = 'three') {
  if (frame === 'three') return new THREE.Matrix3().set(-1, 0, 0, 0, 0, -1, 0, 1, 0);
  if (frame === 'gl') return new THREE.Matrix3().set(1, 0, 0, 0, 0, -1, 0, 1, 0);
  throw new Error(`frame ${frame}: 'three' or 'gl'`);
}

export async function fetchJson(url) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  return r.json();
}

/** Reads a prtkit.sh document (sh-project -o). Returns {doc, order, coefficients: [[r,g,b], …]}. */
export async function loadPrtkitSh(url) {
  const doc = await fetchJson(url);
  if (doc.format !== 'prtkit.sh') throw new Error(`${url}: format ${doc.format}, expected prtkit.sh`);
  if (doc.version !== 1) throw new Error(`${url}: prtkit.sh version ${doc.version}, this reader knows 1`);
  const n = (doc.order + 1) ** 2;
  if (!Array.isArray(doc.coefficients) || doc.coefficients.length !== n) throw new Error(`${url}: ${n} coefficients expected`);
  return { doc, order: doc.order, coefficients: doc.coefficients.map((c) => c.slice(0, 3)) };
}

/**
 * The SH coefficients of the lighting turned by `angle` radians about prtkit's +Z (its up axis),
 * counter-clockwise seen from above: L'(ω) = L(R_z(−angle) ω). Any order: within band l the pair
 * (m, −m) turns by mγ: L'_{l,m} = cos mγ L_{l,m} − sin mγ L_{l,−m},
 * L'_{l,−m} = sin mγ L_{l,m} + cos mγ L_{l,−m}.
 */
export function rotateShZ(coefficients, angle) {
  const out = coefficients.map((c) => c.slice());
  const order = Math.round(Math.sqrt(coefficients.length)) - 1;
  for (let l = 1; l <= order; l++) {
    for (let m = 1; m <= l; m++) {
      const c = Math.cos(m * angle), s = Math.sin(m * angle);
      const ip = l * (l + 1) + m, im = l * (l + 1) - m;
      for (let k = 0; k < 3; k++) {
        const a = coefficients[ip][k], b = coefficients[im][k];
        out[ip][k] = c * a - s * b;
        out[im][k] = s * a + c * b;
      }
    }
  }
  return out;
}

/**
 * Irradiance weights of Ramamoorthi & Hanrahan 2001 (eq. 8–9): the clamped cosine's
 * Â_0 = π, Â_1 = 2π/3, Â_2 = π/4. E(n) = Σ Â_l L_lm Y_lm(n); a Lambert surface of albedo ρ
 * shows ρ E/π — what `render --shading irradiance` computes (docs/render.md).
 */
export const A_HAT = [Math.PI, (2 * Math.PI) / 3, Math.PI / 4];

/** The 9 uniform vectors ρ/π · Â_l · L_lm (order ≤ 2; higher bands are dropped, as render -F 2). */
export function irradianceUniform(coefficients, albedo = 1) {
  const out = [];
  for (let i = 0; i < 9; i++) {
    const l = i === 0 ? 0 : i < 4 ? 1 : 2;
    const c = coefficients[i] ?? [0, 0, 0];
    out.push(new THREE.Vector3(...c.map((x) => (albedo / Math.PI) * A_HAT[l] * x)));
  }
  return out;
}

/** GLSL: prtkitShBasis9 and the irradiance of 9 pre-weighted coefficients, n in prtkit's frame. */
export const SH_GLSL = /* glsl */ `
uniform mat3 prtkitFromWorld;
void prtkitShBasis9(vec3 n, out float Y[9]) {
  Y[0] = 0.28209479177387814;
  Y[1] = 0.4886025119029199 * n.y;
  Y[2] = 0.4886025119029199 * n.z;
  Y[3] = 0.4886025119029199 * n.x;
  Y[4] = 1.0925484305920792 * n.x * n.y;
  Y[5] = 1.0925484305920792 * n.y * n.z;
  Y[6] = 0.31539156525252005 * (3.0 * n.z * n.z - 1.0);
  Y[7] = 1.0925484305920792 * n.x * n.z;
  Y[8] = 0.5462742152960396 * (n.x * n.x - n.y * n.y);
}
uniform vec3 shIrradiance[9]; // albedo/π · Â_l · L_lm
vec3 prtkitShLambert(vec3 n) {
  float Y[9];
  prtkitShBasis9(n, Y);
  vec3 c = vec3(0.0);
  for (int i = 0; i < 9; i++) c += shIrradiance[i] * Y[i];
  return c;
}
`;

// ---- SHRMs ----------------------------------------------------------------------------------

/**
 * A minimal OpenEXR reader for prtkit's SHRM files: one scanline part, FLOAT or HALF channels,
 * compression NONE, ZIPS or ZIP (zlib through the browser's DecompressionStream). three.js's
 * EXRLoader reads only the channels named R, G, B, A (it cannot pick a layer such as `B1-1.R` of a
 * single-part file), so this reads every channel by name. Returns {width, height, channels: Map
 * name → Float32Array, row 0 first}.
 */
export async function readExrChannels(buffer) {
  const dv = new DataView(buffer);
  const bytes = new Uint8Array(buffer);
  if (dv.getUint32(0, true) !== 20000630) throw new Error('not an OpenEXR file');
  const flags = dv.getUint32(4, true) >>> 8;
  if (flags & (0x2 | 0x10 | 0x8)) throw new Error('tiled, deep or multi-part EXR: not supported here');
  let p = 8;
  const cstr = () => { let e = p; while (bytes[e]) e++; const s = new TextDecoder().decode(bytes.subarray(p, e)); p = e + 1; return s; };
  const header = {};
  for (;;) {
    const name = cstr();
    if (!name) break;
    const type = cstr();
    const size = dv.getUint32(p, true); p += 4;
    const start = p;
    if (type === 'chlist') {
      const chans = [];
      while (bytes[p]) { const n = cstr(); chans.push({ name: n, type: dv.getInt32(p, true) }); p += 16; }
      header.channels = chans;
    } else if (type === 'compression') header.compression = bytes[p];
    else if (type === 'box2i' && name === 'dataWindow') header.dataWindow = [0, 1, 2, 3].map((i) => dv.getInt32(start + 4 * i, true));
    p = start + size;
  }
  const [x0, y0, x1, y1] = header.dataWindow;
  const width = x1 - x0 + 1, height = y1 - y0 + 1;
  const linesPerBlock = { 0: 1, 2: 1, 3: 16 }[header.compression];
  if (!linesPerBlock) throw new Error(`EXR compression ${header.compression}: only NONE, ZIPS, ZIP here`);
  const chunks = Math.ceil(height / linesPerBlock);
  const channels = new Map(header.channels.map((c) => [c.name, new Float32Array(width * height)]));
  const sizes = header.channels.map((c) => (c.type === 1 ? 2 : 4)); // 1 HALF, 2 FLOAT (0 UINT: refused below)
  if (header.channels.some((c) => c.type === 0)) throw new Error('UINT EXR channels: not supported here');
  const lineBytes = sizes.reduce((a, b) => a + b, 0) * width;
  for (let k = 0; k < chunks; k++) {
    let q = Number(dv.getBigUint64(p + 8 * k, true));
    const y = dv.getInt32(q, true) - y0;
    const n = dv.getUint32(q + 4, true);
    const lines = Math.min(linesPerBlock, height - y);
    let data = bytes.subarray(q + 8, q + 8 + n);
    if (n < lines * lineBytes) data = unpredict(await inflate(data));
    const view = new DataView(data.buffer, data.byteOffset, data.byteLength);
    let o = 0;
    for (let r = 0; r < lines; r++) {
      header.channels.forEach((c, ci) => {
        const dst = channels.get(c.name);
        const row = (y + r) * width;
        for (let x = 0; x < width; x++, o += sizes[ci]) {
          dst[row + x] = sizes[ci] === 4 ? view.getFloat32(o, true) : THREE.DataUtils.fromHalfFloat(view.getUint16(o, true));
        }
      });
    }
  }
  return { width, height, channels };
}
async function inflate(data) {
  const stream = new Blob([data]).stream().pipeThrough(new DecompressionStream('deflate'));
  return new Uint8Array(await new Response(stream).arrayBuffer());
}
function unpredict(t) { // OpenEXR's ZIP predictor and byte interleave, undone
  for (let i = 1; i < t.length; i++) t[i] = (t[i - 1] + t[i] - 128) & 0xff;
  const out = new Uint8Array(t.length);
  const half = (t.length + 1) >> 1;
  for (let i = 0, a = 0, b = half; i < t.length; ) { out[i++] = t[a++]; if (i < t.length) out[i++] = t[b++]; }
  return out;
}

/**
 * Reads a prtkit.shrm document and its EXR (the `shrm_file` it names: beside the document, or
 * where `urlOf(name)` says, e.g. the object URL of a dropped file): a THREE.DataArrayTexture with one RGBA32F layer per B_pq (index p(p+1)+q),
 * each a lat-long map of reflection directions R (row 0: R = +Z, column 0: φ = 0, texel centres at
 * half-integers), linearly filtered, repeating in φ.
 */
export async function loadPrtkitShrm(url, urlOf = undefined) {
  const doc = await fetchJson(url);
  if (doc.format !== 'prtkit.shrm') throw new Error(`${url}: format ${doc.format}, expected prtkit.shrm`);
  if (doc.method !== 'frequency') throw new Error(`${url}: method ${doc.method}: only frequency SHRMs have an EXR`);
  if (doc.layout !== 'latlong') throw new Error(`${url}: layout ${doc.layout}: only latlong here`);
  if (doc.parameterization !== 'reflection') throw new Error(`${url}: parameterization ${doc.parameterization}: only reflection here`);
  const base = url.slice(0, url.lastIndexOf('/') + 1);
  const name = doc.shrm_file.split('/').pop();
  const file = urlOf ? urlOf(name) : base + name;
  const r = await fetch(file);
  if (!r.ok) throw new Error(`${file}: HTTP ${r.status}`);
  const exr = await readExrChannels(await r.arrayBuffer());
  const { width, height } = exr;
  const layers = doc.layers.length;
  if (layers !== (doc.p_b + 1) ** 2) throw new Error(`${url}: ${layers} layers for P_B = ${doc.p_b}`);
  const data = new Float32Array(width * height * 4 * layers);
  doc.layers.forEach((name, i) => {
    const ch = ['R', 'G', 'B'].map((c) => exr.channels.get(`${name}.${c}`));
    if (ch.some((x) => !x)) throw new Error(`${file}: layer ${name} missing`);
    const o = i * width * height * 4;
    for (let t = 0; t < width * height; t++) {
      data[o + 4 * t] = ch[0][t]; data[o + 4 * t + 1] = ch[1][t]; data[o + 4 * t + 2] = ch[2][t]; data[o + 4 * t + 3] = 1;
    }
  });
  const texture = new THREE.DataArrayTexture(data, width, height, layers);
  texture.format = THREE.RGBAFormat;
  texture.type = THREE.FloatType;
  texture.minFilter = texture.magFilter = THREE.LinearFilter; // needs OES_texture_float_linear
  texture.wrapS = THREE.RepeatWrapping;
  texture.wrapT = THREE.ClampToEdgeWrapping;
  texture.generateMipmaps = false;
  texture.flipY = false;
  texture.needsUpdate = true;
  return { doc, texture, width, height, pb: doc.p_b, global: doc.global };
}

/**
 * GLSL: B(R, ω_o) = Σ_pq B_pq(R) Y_pq(ω_o′) (R&H 2002 eq. 6), ω_o′ the view direction in the
 * texel's local frame R_z(β)·R_y(α) (docs/formats/shrm.md). The B_pq maps are the SHRM's
 * C_{lm,pq} already summed over the lighting's (l, m) at each R: the EXR stores B_pq(α, β), so
 * per pixel only the view bands are summed. Rotation of the environment about the up axis turns
 * the lookup (β − γ; the local frames turn with it, so ω_o′ is unchanged). Y_pq for p ≤ 8.
 */
export const SHRM_GLSL = /* glsl */ `
precision highp sampler2DArray;
uniform sampler2DArray shrmLayers;
uniform int shrmPB;
uniform int shrmGlobal;
uniform float envTurn; // radians, about prtkit's +Z
const float PI = 3.141592653589793;
float shFactorial(int n) { float f = 1.0; for (int i = 2; i <= n; i++) f *= float(i); return f; }
// Real orthonormal Y_pq(θ, φ), no Condon–Shortley phase.
float shY(int l, int m, float ct, float phi) {
  int am = m < 0 ? -m : m;
  float st = sqrt(max(0.0, 1.0 - ct * ct));
  float pmm = 1.0;                       // P_m^m = (2m−1)!! sin^m θ (no (−1)^m)
  for (int i = 1; i <= am; i++) pmm *= float(2 * i - 1) * st;
  float plm = pmm;
  if (l > am) {
    float p1 = ct * float(2 * am + 1) * pmm;
    float p0 = pmm;
    plm = p1;
    for (int ll = am + 2; ll <= l; ll++) {
      float p2 = (ct * float(2 * ll - 1) * p1 - float(ll + am - 1) * p0) / float(ll - am);
      p0 = p1; p1 = p2; plm = p2;
    }
  }
  float k = sqrt(float(2 * l + 1) / (4.0 * PI) * shFactorial(l - am) / shFactorial(l + am));
  if (m == 0) return k * plm;
  return sqrt(2.0) * k * plm * (m > 0 ? cos(float(am) * phi) : sin(float(am) * phi));
}
// R and wo (towards the viewer) in prtkit's frame.
vec3 prtkitShrm(vec3 R, vec3 wo) {
  float alpha = acos(clamp(R.z, -1.0, 1.0));
  float beta = atan(R.y, R.x);
  float u = (beta - envTurn) / (2.0 * PI);
  vec2 uv = vec2(u - floor(u), alpha / PI);
  vec3 w = wo;
  if (shrmGlobal == 0) { // local SHRM: ω_o in the texel's frame (R_z(β) R_y(α))ᵀ ω_o
    float cb = cos(beta), sb = sin(beta), ca = cos(alpha), sa = sin(alpha);
    vec3 t = vec3(cb * wo.x + sb * wo.y, -sb * wo.x + cb * wo.y, wo.z); // R_z(−β)
    w = vec3(ca * t.x - sa * t.z, t.y, sa * t.x + ca * t.z);             // R_y(−α)
  } else { // global: the world view direction, turned with the environment
    float c = cos(envTurn), s = sin(envTurn);
    w = vec3(c * wo.x + s * wo.y, -s * wo.x + c * wo.y, wo.z);
  }
  float ct = clamp(w.z, -1.0, 1.0), phi = atan(w.y, w.x);
  vec3 B = vec3(0.0);
  for (int p = 0; p <= 8; p++) {
    if (p > shrmPB) break;
    for (int q = -p; q <= p; q++) {
      B += texture(shrmLayers, vec3(uv, float(p * (p + 1) + q))).rgb * shY(p, q, ct, phi);
    }
  }
  return B;
}
`;

// ---- encode-normals -------------------------------------------------------------------------

/**
 * Reads `encode-normals` codes (words layout, b ≤ 32: one little-endian u32 or u16 per normal)
 * into a W×H THREE.DataTexture of unsigned integers (R32UI, usampler2D, texelFetch), row 0 = the
 * first W codes. The report (prtkit.normal-codes) says the scheme, bits and layout; the GLSL
 * decoder is `encode-normals --emit-decoder glsl --scheme S --bits B` (prtkit_decode_normal(uint)).
 */
export async function loadNormalCodes(codesUrl, reportUrl, width, height) {
  const report = await fetchJson(reportUrl);
  if (report.format !== 'prtkit.normal-codes') throw new Error(`${reportUrl}: format ${report.format}`);
  if (report.layout.stream !== 'words' || report.bits > 32) throw new Error(`${reportUrl}: only word streams of ≤ 32 bits here`);
  if (report.count !== width * height) throw new Error(`${reportUrl}: ${report.count} codes, not ${width}×${height}`);
  const r = await fetch(codesUrl);
  if (!r.ok) throw new Error(`${codesUrl}: HTTP ${r.status}`);
  const buf = await r.arrayBuffer();
  const words = report.layout.word_bytes === 2 ? Uint32Array.from(new Uint16Array(buf)) : new Uint32Array(buf);
  const texture = new THREE.DataTexture(words, width, height, THREE.RedIntegerFormat, THREE.UnsignedIntType);
  texture.internalFormat = 'R32UI';
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.flipY = false;
  texture.needsUpdate = true;
  return { report, texture };
}

// ---- PRT relighting (transfer --glb) --------------------------------------------------------

/**
 * The transfer .glb's vec4 attributes as three.js names them: GLTFLoader lower-cases the names
 * it does not know, so `_PRT_k` arrives as geometry attribute `_prt_k`.
 */
export const prtAttribute = (k) => `_prt_${k}`;

/**
 * The lighting uniform of the PRT vertex shader, one vec3 per value the K attributes hold (4K,
 * zero-padded): for a grey bake the (rotated) lighting SH L_i of its n bands; for a coloured bake
 * (`channels` 3: 3 × `coeffs` values channel-major, docs/formats/transfer.md) value c·n² + i gets
 * L_i's channel c alone, so the same Σ_v lighting[v] · T_v gives B_c = Σ_i T_ci L_ci.
 */
export function transferLightingUniform(coefficients, count, channels = 1, coeffs = count) {
  return Array.from({ length: count }, (_, v) => {
    if (channels === 1) return new THREE.Vector3(...(coefficients[v] ?? [0, 0, 0]));
    const c = Math.floor(v / coeffs), light = coefficients[v % coeffs] ?? [0, 0, 0];
    const masked = [0, 0, 0];
    if (c < 3) masked[c] = light[c];
    return new THREE.Vector3(...masked);
  });
}

/**
 * GLSL vertex shader of PRT relighting (docs/formats/transfer.md): B = Σ_i T_i L_i at the vertex,
 * four coefficients per attribute (one mat4x3 of lighting times one vec4 of transfer), passed on
 * as a varying and interpolated over the triangle (Gouraud, as `render --shading transfer`).
 * K attributes beside position: WebGL2 guarantees 16 vertex attributes, so K ≤ 15 (n ≤ 7 bands;
 * prtTextureVertexShader past that).
 */
export function prtVertexShader(K) {
  const attributes = Array.from({ length: K }, (_, k) => `attribute vec4 ${prtAttribute(k)};`).join('\n');
  const sum = Array.from({ length: K }, (_, k) =>
    `  c += mat4x3(shLighting[${4 * k}], shLighting[${4 * k + 1}], shLighting[${4 * k + 2}], shLighting[${4 * k + 3}]) * ${prtAttribute(k)};`).join('\n');
  return /* glsl */ `
${attributes}
uniform vec3 shLighting[${4 * K}]; // L_i, turned by the environment rotation
varying vec3 vRadiance;
void main() {
  vec3 c = vec3(0.0);
${sum}
  vRadiance = c;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;
}
/**
 * The same diffuse relighting as prtVertexShader for a bake of more four-vectors than WebGL 2's
 * guaranteed attributes leave (K > 15: n = 8 bands, 16 four-vectors), the transfer read from
 * transferTexture by gl_VertexID: B = Σ_i T_i L_i, one mat4x3 per texel.
 */
export function prtTextureVertexShader(K) {
  const sum = Array.from({ length: K }, (_, k) =>
    `  c += mat4x3(shLighting[${4 * k}], shLighting[${4 * k + 1}], shLighting[${4 * k + 2}], shLighting[${4 * k + 3}]) * transferTexel(base + ${k});`).join('\n');
  return /* glsl */ `
uniform sampler2D prtTransfer; // RGBA32F, ${TRANSFER_TEXTURE_WIDTH} wide: vertex v's ${K} texels from v·${K}
uniform vec3 shLighting[${4 * K}]; // L_i, turned by the environment rotation
varying vec3 vRadiance;
vec4 transferTexel(int q) { return texelFetch(prtTransfer, ivec2(q % ${TRANSFER_TEXTURE_WIDTH}, q / ${TRANSFER_TEXTURE_WIDTH}), 0); }
void main() {
  int base = gl_VertexID * ${K};
  vec3 c = vec3(0.0);
${sum}
  vRadiance = c;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;
}
export const PRT_FRAGMENT = /* glsl */ `
uniform float exposureScale;
varying vec3 vRadiance;
void main() { gl_FragColor = linearToOutputTexel(vec4(vRadiance * exposureScale, 1.0)); }`;

// ---- Glossy PRT (transfer --factors --glb) --------------------------------------------------

/** Width of the transfer texture: vertex v's P texels start at linear texel v·P. */
export const TRANSFER_TEXTURE_WIDTH = 2048;

/**
 * A bake's transfer as an RGBA32F THREE.DataTexture: the values of each vertex (the `_PRT_k`
 * stream: n² of a diffuse bake, K·n² term-major of a glossy one, σ_k folded in) as
 * P = ⌈values/4⌉ consecutive texels, vertex v's texel p at linear index v·P + p of a
 * TRANSFER_TEXTURE_WIDTH-wide image (row-major). WebGL 2 draws at most 16 attributes per vertex;
 * the vertex shaders of glossy bakes and of diffuse bakes past 15 four-vectors (n = 8) read these
 * by gl_VertexID instead.
 */
export function transferTexture(geometry, texelsPerVertex) {
  const vertices = geometry.attributes.position.count;
  const W = TRANSFER_TEXTURE_WIDTH;
  const H = Math.ceil((vertices * texelsPerVertex) / W);
  const data = new Float32Array(W * H * 4);
  for (let p = 0; p < texelsPerVertex; p++) {
    const a = geometry.attributes[prtAttribute(p)];
    if (!a || a.count !== vertices) throw new Error(`the bake lacks ${prtAttribute(p)} for its ${vertices} vertices`);
    for (let v = 0; v < vertices; v++) {
      const o = 4 * (v * texelsPerVertex + p);
      data[o] = a.getX(v); data[o + 1] = a.getY(v); data[o + 2] = a.getZ(v); data[o + 3] = a.getW(v);
    }
  }
  const texture = new THREE.DataTexture(data, W, H, THREE.RGBAFormat, THREE.FloatType);
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.generateMipmaps = false;
  texture.flipY = false;
  texture.needsUpdate = true;
  return texture;
}

/**
 * h_0 … h_{K−1} (the .glb's `glossy.h` blob, K·N² floats) as the R32F texture the emitted
 * snippet reads (N wide, K·N tall, texel (k, t·N + j) = h_t of cell (j, k)): the blob as it is.
 */
export function glossyHTexture(values, resolution, terms) {
  if (values.length !== terms * resolution * resolution) throw new Error(`glossy.h: ${values.length} values, not K·N² = ${terms * resolution * resolution}`);
  const texture = new THREE.DataTexture(values, resolution, terms * resolution, THREE.RedFormat, THREE.FloatType);
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.generateMipmaps = false;
  texture.flipY = false;
  texture.needsUpdate = true;
  return texture;
}

/** GLSL lines packing the K sums c[t] into the ⌈3K/4⌉ vec4 varyings vC (zeros pad the last). */
function packGlossyVaryings(K) {
  const Q = Math.ceil((3 * K) / 4);
  const f = (i) => (i < 3 * K ? `c[${Math.floor(i / 3)}].${'xyz'[i % 3]}` : '0.0');
  return Array.from({ length: Q }, (_, q) => `  vC[${q}] = vec4(${[0, 1, 2, 3].map((j) => f(4 * q + j)).join(', ')});`).join('\n');
}

/**
 * Vertex shader of glossy PRT (Mahajan, Tseng & Ramamoorthi 2008, eq. 4): c_t = Σ_i T_ti L_i for
 * the K terms at the vertex, T read from the transfer texture by gl_VertexID, L the (rotated)
 * lighting's n² coefficients; the 3K numbers packed into ⌈3K/4⌉ vec4 varyings (interpolated
 * over the triangle, as render interpolates c_k with the hit's barycentrics), with the normal
 * and position in prtkit's frame (the mesh's own axes).
 */
export function prtGlossyVertexShader(K, coeffs) {
  const values = K * coeffs, P = Math.ceil(values / 4), Q = Math.ceil((3 * K) / 4);
  const pack = packGlossyVaryings(K);
  // Written out texel by texel with constant indices (value i = 4p + j is term ⌊i/n²⌋'s
  // coefficient i mod n²): a four-vector inside one term is one mat4x3 product, as the diffuse
  // shader's; one that straddles two terms (n odd) is taken component by component.
  const sum = [];
  for (let p = 0; p < P; p++) {
    sum.push(`  T = transferTexel(base + ${p});`);
    const i0 = 4 * p, t = Math.floor(i0 / coeffs), k = i0 % coeffs;
    if (k + 4 <= coeffs && i0 + 4 <= values) {
      sum.push(`  c[${t}] += mat4x3(shLighting[${k}], shLighting[${k + 1}], shLighting[${k + 2}], shLighting[${k + 3}]) * T;`);
    } else {
      for (let j = 0; j < 4 && i0 + j < values; j++) {
        const i = i0 + j;
        sum.push(`  c[${Math.floor(i / coeffs)}] += T.${'xyzw'[j]} * shLighting[${i % coeffs}];`);
      }
    }
  }
  return /* glsl */ `
uniform sampler2D prtTransfer; // RGBA32F, ${TRANSFER_TEXTURE_WIDTH} wide: vertex v's ${P} texels from v·${P}
uniform vec3 shLighting[${coeffs}]; // L_i, turned by the environment rotation
varying vec4 vC[${Q}];
varying vec3 vNormal;
varying vec3 vPosition;
vec4 transferTexel(int q) { return texelFetch(prtTransfer, ivec2(q % ${TRANSFER_TEXTURE_WIDTH}, q / ${TRANSFER_TEXTURE_WIDTH}), 0); }
void main() {
  vec3 c[${K}];
  for (int t = 0; t < ${K}; t++) c[t] = vec3(0.0);
  int base = gl_VertexID * ${P};
  vec4 T;
${sum.join('\n')}
${pack}
  vNormal = normal;
  vPosition = position;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;
}

/**
 * Fragment shader of glossy PRT: `snippet` is `transfer --glsl`'s output for the bake (its
 * prtkitGlossyRadiance: the view direction in the normal's frame F = R_z(φ_n) R_y(θ_n) R_z(−φ_n) and the
 * h_k lookup with render's bilinear/pole rule, reading the uniform prtkitGlossyHTexture). The normal is
 * turned towards the viewer first, as render shades the side it sees.
 */
export function prtGlossyFragmentShader(snippet, K) {
  const Q = Math.ceil((3 * K) / 4);
  const unpack = Array.from({ length: K }, (_, t) =>
    `  c[${t}] = vec3(${[0, 1, 2].map((j) => { const i = 3 * t + j; return `vC[${Math.floor(i / 4)}].${'xyzw'[i % 4]}`; }).join(', ')});`).join('\n');
  return /* glsl */ `
${snippet}
uniform mat3 prtkitFromWorld;
uniform float exposureScale;
varying vec4 vC[${Q}];
varying vec3 vNormal;
varying vec3 vPosition;
void main() {
  vec3 c[PRTKIT_GLOSSY_TERMS];
${unpack}
  vec3 wo = normalize(prtkitFromWorld * cameraPosition - vPosition); // towards the eye, prtkit's frame
  vec3 n = normalize(vNormal);
  if (dot(n, wo) < 0.0) n = -n;
  gl_FragColor = linearToOutputTexel(vec4(prtkitGlossyRadiance(n, wo, c) * exposureScale, 1.0));
}`;
}

// ---- Clustered PCA (transfer --clusters C --pca P) -------------------------------------------
//
// A compressed bake has no _PRT_k attributes: each vertex holds its cluster c (`_PRT_CLUSTER`, a
// float) and P weights (`_PRT_W_k`, four a vec4, zeros padding), and the .glb's blobs hold every
// cluster's mean m_c (C × D) and directions b_cp (C × P × D), D = K·n² values (K = 1 diffuse;
// term-major for a glossy bake), so that T(x) = m_c + Σ_p w_p(x) b_cp (Sloan, Hall, Hart &
// Snyder 2003, eq. 2). Relighting stays in compressed form (eq. 3): per frame the C·(P + 1)·K
// dot products of the lighting with n² values each, m_ck·L and b_cpk·L (`projectCpcaLighting`,
// on the CPU), go to a small float texture; the vertex shader reads its cluster's 1 + P texels per
// term and takes P multiply-adds per term: c_k(x) = m_ck·L + Σ_p w_p(x) (b_cpk·L).

/** three.js's names of the compressed bake's attributes (GLTFLoader lower-cases them). */
export const PRT_CLUSTER_ATTRIBUTE = '_prt_cluster';
export const prtWeightAttribute = (k) => `_prt_w_${k}`;

/** Width of the projected-lighting texture: cluster c's (1 + P)·K texels from linear index c·(1 + P)·K. */
export const CPCA_LIGHTING_WIDTH = 2048;

/**
 * The compressed bake as the page keeps it: `means` (C·D) and `bases` (C·P·D) as the .glb's blobs
 * hold them, and an RGBA32F texture for the projected lighting, texel (c·(1 + P) + j)·K + k (row-
 * major, CPCA_LIGHTING_WIDTH wide) = m_ck·L for j = 0 and b_c(j−1)k·L for j ≥ 1, rgb.
 */
export function cpcaBake(clusters, components, terms, coeffs, means, bases, channels = 1) {
  const D = channels * terms * coeffs;
  if (means.length !== clusters * D) throw new Error(`cpca.means: ${means.length} values, not C·D = ${clusters * D}`);
  if (bases.length !== clusters * components * D) throw new Error(`cpca.bases: ${bases.length} values, not C·P·D = ${clusters * components * D}`);
  const texels = clusters * (1 + components) * terms;
  const W = CPCA_LIGHTING_WIDTH, H = Math.ceil(texels / W);
  const data = new Float32Array(W * H * 4);
  const texture = new THREE.DataTexture(data, W, H, THREE.RGBAFormat, THREE.FloatType);
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.generateMipmaps = false;
  texture.flipY = false;
  texture.needsUpdate = true;
  return { clusters, components, terms, coeffs, channels, means, bases, texture };
}

/**
 * One frame of eq. 3's per-cluster half: the lighting (RGB SH, ≥ n² coefficients, already turned)
 * dotted with each cluster's mean and directions, term by term, into the texture (marked for
 * upload). C·(1 + P)·K·n² multiply-adds per channel, in double precision.
 */
export function projectCpcaLighting(cpca, lighting) {
  const { clusters: C, components: P, terms: K, coeffs: N, channels, means, bases, texture } = cpca;
  const D = channels * K * N, data = texture.image.data;
  const Lr = new Float64Array(N), Lg = new Float64Array(N), Lb = new Float64Array(N);
  for (let i = 0; i < N; i++) [Lr[i], Lg[i], Lb[i]] = lighting[i] ?? [0, 0, 0];
  let o = 0;
  for (let c = 0; c < C; c++) {
    for (let j = 0; j <= P; j++) {
      const src = j === 0 ? means : bases, start = j === 0 ? c * D : (c * P + j - 1) * D;
      for (let k = 0; k < K; k++, o += 4) {
        let r = 0, g = 0, b = 0;
        if (channels === 1) {
          for (let i = 0, s = start + k * N; i < N; i++, s++) {
            const t = src[s];
            r += t * Lr[i]; g += t * Lg[i]; b += t * Lb[i];
          }
        } else {
          // A coloured bake (K = 1): channel c's n² values dotted with channel c of the lighting.
          for (let i = 0; i < N; i++) {
            r += src[start + i] * Lr[i]; g += src[start + N + i] * Lg[i]; b += src[start + 2 * N + i] * Lb[i];
          }
        }
        data[o] = r; data[o + 1] = g; data[o + 2] = b; data[o + 3] = 1;
      }
    }
  }
  texture.needsUpdate = true;
}

/**
 * Vertex shader of compressed PRT: the vertex's cluster c and weights w_p (attributes), its
 * cluster's projected lighting read from the texture, and for each term k
 *   c_k = (m_ck·L) + Σ_p w_p (b_cpk·L)          (Sloan et al. 2003, eq. 3)
 * written out with constant indices (K·(1 + P) texel fetches, K·P vec3 multiply-adds). Diffuse
 * (`glossy` false, K = 1): B = c_0 goes on as vRadiance, for PRT_FRAGMENT. Glossy: the c_k are
 * packed into vC, with the normal and position, for prtGlossyFragmentShader — as the uncompressed
 * glossy vertex shader hands them on.
 */
export function prtCpcaVertexShader(K, P, glossy) {
  const A = Math.ceil(P / 4);
  const attributes = [`attribute float ${PRT_CLUSTER_ATTRIBUTE};`,
    ...Array.from({ length: A }, (_, a) => `attribute vec4 ${prtWeightAttribute(a)};`)].join('\n');
  const w = (p) => `${prtWeightAttribute(Math.floor(p / 4))}.${'xyzw'[p % 4]}`;
  const sums = Array.from({ length: K }, (_, k) => {
    const terms = [`cpcaTexel(base + ${k})`, ...Array.from({ length: P }, (_, p) => `${w(p)} * cpcaTexel(base + ${(1 + p) * K + k})`)];
    return `  c[${k}] = ${terms.join('\n         + ')};`;
  }).join('\n');
  const out = glossy
    ? `${packGlossyVaryings(K)}
  vNormal = normal;
  vPosition = position;`
    : '  vRadiance = c[0];';
  const varyings = glossy ? `varying vec4 vC[${Math.ceil((3 * K) / 4)}];\nvarying vec3 vNormal;\nvarying vec3 vPosition;` : 'varying vec3 vRadiance;';
  return /* glsl */ `
${attributes}
uniform sampler2D cpcaLighting; // RGBA32F, ${CPCA_LIGHTING_WIDTH} wide: cluster c's ${(1 + P) * K} texels from c·${(1 + P) * K}
${varyings}
vec3 cpcaTexel(int q) { return texelFetch(cpcaLighting, ivec2(q % ${CPCA_LIGHTING_WIDTH}, q / ${CPCA_LIGHTING_WIDTH}), 0).rgb; }
void main() {
  vec3 c[${K}];
  int base = int(${PRT_CLUSTER_ATTRIBUTE} + 0.5) * ${(1 + P) * K};
${sums}
${out}
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;
}
