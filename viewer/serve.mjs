// A static file server for the viewer, on 127.0.0.1 only:
//   node viewer/serve.mjs [DIR] [--port P]
// serves the repository (the viewer, its node_modules and shaders/) and,
// under /data/, DIR (a directory the host wrote with --instances), then
// prints the viewer's address. Port 0 picks a free one. The render test
// imports serve() from here.
import { createReadStream } from 'node:fs';
import { stat } from 'node:fs/promises';
import { createServer } from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const REPO = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const TYPES = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.mjs': 'text/javascript; charset=utf-8',
  '.json': 'application/json',
  '.bin': 'application/octet-stream',
  '.png': 'image/png',
  '.vert': 'text/plain; charset=utf-8',
  '.frag': 'text/plain; charset=utf-8',
};

// Resolves a URL path under `root`; null if it would leave it.
function under(root, urlPath) {
  const file = path.resolve(root, `.${path.posix.normalize(`/${urlPath}`)}`);
  return file === root || file.startsWith(root + path.sep) ? file : null;
}

export function serve({ data, port = 0, host = '127.0.0.1' } = {}) {
  const dataRoot = data ? path.resolve(data) : null;
  const server = createServer(async (req, res) => {
    const urlPath = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    let file = dataRoot && urlPath.startsWith('/data/') ? under(dataRoot, urlPath.slice('/data/'.length)) : under(REPO, urlPath);
    try {
      if (file && (await stat(file)).isDirectory()) file = path.join(file, 'index.html');
      if (!file || !(await stat(file)).isFile()) throw new Error('not a file');
    } catch {
      res.writeHead(404, { 'content-type': 'text/plain' });
      res.end(`not found: ${urlPath}\n`);
      return;
    }
    res.writeHead(200, { 'content-type': TYPES[path.extname(file)] ?? 'application/octet-stream', 'cache-control': 'no-store' });
    createReadStream(file).pipe(res);
  });
  return new Promise((resolve, reject) => {
    server.once('error', reject);
    server.listen(port, host, () => resolve({ server, url: `http://${host}:${server.address().port}` }));
  });
}

if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  const args = process.argv.slice(2);
  const portAt = args.indexOf('--port');
  const port = portAt >= 0 ? Number(args.splice(portAt, 2)[1]) : 8000;
  const data = args[0];
  const { url } = await serve({ data, port });
  console.log(data ? `viewer: ${url}/viewer/?data=/data/` : `serving ${REPO} at ${url}/ (viewer: ${url}/viewer/?data=PATH/)`);
}
