// A tiny static server for the viewer, on 127.0.0.1 only.
//   node viewer/serve.mjs [--port N] [--bake DIR] [--query '?mode=…']
// Serves the repository root (the page is /viewer/, its modules under /viewer/node_modules/) and,
// with --bake, DIR under /bake/. Prints the URL. Exported as serve() for the tests.
import { createServer } from 'node:http';
import { createReadStream, statSync } from 'node:fs';
import { resolve, join, extname, sep } from 'node:path';
import { fileURLToPath } from 'node:url';

const TYPES = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript', '.mjs': 'text/javascript',
  '.json': 'application/json', '.png': 'image/png', '.css': 'text/css', '.glsl': 'text/plain',
  '.ktx2': 'image/ktx2', '.dds': 'application/octet-stream', '.wasm': 'application/wasm', '.hdr': 'application/octet-stream', '.exr': 'application/octet-stream',
};

export function serve({ root, bake = null, port = 0, quiet = true } = {}) {
  const mounts = [];
  if (bake) mounts.push(['/bake/', resolve(bake)]);
  mounts.push(['/', resolve(root)]);
  const server = createServer((req, res) => {
    let path;
    try { path = decodeURIComponent(new URL(req.url, 'http://x').pathname); } catch { res.writeHead(400).end(); return; }
    const [prefix, dir] = mounts.find(([p]) => path.startsWith(p));
    let file = resolve(join(dir, path.slice(prefix.length)));
    if (file !== dir && !file.startsWith(dir + sep)) { res.writeHead(403).end(); return; }
    try {
      if (statSync(file).isDirectory()) file = join(file, 'index.html');
      statSync(file);
    } catch { res.writeHead(404).end('not found'); if (!quiet) console.log('404', path); return; }
    res.writeHead(200, { 'content-type': TYPES[extname(file)] ?? 'application/octet-stream', 'cache-control': 'no-store' });
    createReadStream(file).pipe(res);
  });
  return new Promise((ok) => server.listen(port, '127.0.0.1', () => ok(server)));
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  const args = process.argv.slice(2);
  const opt = (name) => { const i = args.indexOf(name); return i >= 0 ? args[i + 1] : undefined; };
  const root = resolve(fileURLToPath(new URL('..', import.meta.url)));
  const bake = opt('--bake');
  const server = await serve({ root, bake, port: Number(opt('--port') ?? 8333), quiet: false });
  const { port } = server.address();
  const query = opt('--query') ?? (bake ? '?ibl=/bake/' : ''); // what to open: view.sh says
  console.log(`prtkit viewer: http://127.0.0.1:${port}/viewer/${query}`);
  console.log('(Ctrl-C to stop)');
}
