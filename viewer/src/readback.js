// readback.js — the test hook every page shares: the drawn frame read back for test/run.mjs.

/**
 * The `width`×`height` RGBA8 frame of `gl`'s default framebuffer, rows bottom-up, as base64
 * (puppeteer hands strings across; the bytes go in 32 KiB slices through String.fromCharCode).
 */
export function readFrame(gl, width, height) {
  const buf = new Uint8Array(width * height * 4);
  gl.readPixels(0, 0, width, height, gl.RGBA, gl.UNSIGNED_BYTE, buf);
  let s = '';
  for (let i = 0; i < buf.length; i += 0x8000) s += String.fromCharCode.apply(null, buf.subarray(i, i + 0x8000));
  return { width, height, rgbaBottomUp: btoa(s) };
}

/**
 * The hook an engine page (`engines/*.js`) exposes to test/run.mjs, as the three.js viewer does:
 * window.prtkit = { errors, ready, pixels(), gpu() }. `setup()` loads the bake (its failure is
 * recorded in `errors`); `pixels()` draws one frame with `draw()`, reads it back from the context
 * `context()` returns, and records any WebGL error.
 */
export function exposeEnginePage({ errors, setup, draw, context, width, height, gpu }) {
  window.prtkit = {
    errors,
    ready: setup().catch((e) => { errors.push(String(e.stack ?? e)); return false; }),
    pixels() {
      draw();
      const gl = context();
      const frame = readFrame(gl, width, height);
      const e = gl.getError();
      if (e !== gl.NO_ERROR) errors.push(`WebGL error 0x${e.toString(16)}`);
      return frame;
    },
    gpu,
  };
}
