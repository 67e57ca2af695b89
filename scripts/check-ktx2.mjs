// Validates KTX 2.0 files with ktx-parse (the parser three.js and glTF-Transform use), plus the
// layout rules of the KTX 2.0 specification that a parser does not enforce: level sizes for the
// format, lcm(texel block size, 4) alignment of every level, levels stored smallest first, the
// Basic DFD's size and bytesPlane0, and KTXorientation = "rd".
// Usage: node check-ktx2.mjs FILE.ktx2... (run through scripts/check-ktx2.sh, which installs
// ktx-parse). Prints one line per file; exits 1 if any file fails.
import { readFileSync } from 'node:fs';
import { read } from 'ktx-parse';

// Texel block sizes of the formats prtkit writes (VkFormat → bytes).
const TEXEL_BYTES = { 97: 8, 109: 16, 122: 4, 123: 4, 83: 4, 103: 8 };

function check(path) {
  const bytes = new Uint8Array(readFileSync(path));
  const ktx = read(bytes);
  const texel = TEXEL_BYTES[ktx.vkFormat];
  if (texel === undefined) throw new Error(`unexpected vkFormat ${ktx.vkFormat}`);
  if (ktx.supercompressionScheme !== 0) throw new Error('supercompressed');
  if (ktx.faceCount !== 1 && ktx.faceCount !== 6) throw new Error(`faceCount ${ktx.faceCount}`);
  if (ktx.faceCount === 6 && (ktx.pixelWidth !== ktx.pixelHeight || ktx.pixelDepth !== 0)) {
    throw new Error('a cube map must have square faces and depth 0');
  }
  if (ktx.layerCount !== 0) throw new Error(`layerCount ${ktx.layerCount}`);
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const align = texel; // lcm(texel, 4) = texel for the block sizes 4, 8 and 16 above
  let previous = Infinity;
  ktx.levels.forEach((level, p) => {
    const w = Math.max(1, ktx.pixelWidth >> p);
    const h = Math.max(1, ktx.pixelHeight >> p);
    const want = ktx.faceCount * w * h * texel;
    if (level.levelData.byteLength !== want || level.uncompressedByteLength !== want) {
      throw new Error(`level ${p}: ${level.levelData.byteLength} bytes, expected ${want}`);
    }
    const offset = Number(view.getBigUint64(80 + 24 * p, true));
    if (offset % align !== 0) throw new Error(`level ${p} at ${offset} is not ${align}-aligned`);
    if (offset >= previous) throw new Error(`level ${p} is not stored before level ${p - 1}`);
    previous = offset;
  });
  const dfd = ktx.dataFormatDescriptor[0];
  // ktx-parse does not report the block size; read it (and dfdTotalSize) from the bytes.
  const dfdOffset = view.getUint32(48, true);
  const blockSize = view.getUint16(dfdOffset + 10, true);
  if (blockSize !== 24 + 16 * dfd.samples.length || view.getUint32(dfdOffset, true) !== 4 + blockSize) {
    throw new Error(`DFD block size ${blockSize} for ${dfd.samples.length} samples`);
  }
  if (dfd.bytesPlane[0] !== texel) throw new Error(`DFD bytesPlane0 ${dfd.bytesPlane[0]}`);
  if (dfd.colorModel !== 1 || dfd.transferFunction !== 1) throw new Error('DFD is not linear RGBSDA');
  const orientation = ktx.keyValue.KTXorientation;
  const text = typeof orientation === 'string' ? orientation : new TextDecoder().decode(orientation ?? new Uint8Array());
  if (text.replace(/\0$/, '') !== 'rd') throw new Error(`KTXorientation ${JSON.stringify(text)}`);
  return `vkFormat ${ktx.vkFormat}, ${ktx.faceCount === 6 ? 'cube' : '2-D'} ${ktx.pixelWidth}x${ktx.pixelHeight}, ` +
    `${ktx.levels.length} level(s), ${dfd.samples.length} DFD samples, writer ${JSON.stringify(ktx.keyValue.KTXwriter)}`;
}

let failed = 0;
for (const path of process.argv.slice(2)) {
  try {
    console.log(`ok   ${path}: ${check(path)}`);
  } catch (e) {
    failed += 1;
    console.log(`FAIL ${path}: ${e.message}`);
  }
}
process.exit(failed ? 1 : 0);
