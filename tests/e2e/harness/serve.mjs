// The server of dist/ (same MIME types and no-cache as www/serve.py), with
// tests/e2e/hooks.js first in index.html and the test folders under /__e2e/fs/.
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import { ROOT } from './base.mjs';

const MIME = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript', '.mjs': 'text/javascript',
  '.wasm': 'application/wasm', '.css': 'text/css', '.svg': 'image/svg+xml', '.png': 'image/png',
  '.jpg': 'image/jpeg', '.txt': 'text/plain; charset=utf-8', '.md': 'text/markdown; charset=utf-8',
  '.json': 'application/json',
};
const HOOKS = fs.readFileSync(path.join(ROOT, 'tests/e2e/hooks.js'));

/**
 * Serves `dist` on a free localhost port; resolves to its base URL and a close(). With
 * `hooks`, index.html loads tests/e2e/hooks.js first.
 */
export async function serve(dist, { hooks = true } = {}) {
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://x');
    let file;
    let body;
    if (url.pathname === '/__e2e/hooks.js') {
      body = HOOKS;
      file = 'hooks.js';
    } else if (url.pathname.startsWith('/__e2e/fs/')) {
      // Only files under the system's temp dir and the repository: the test folders.
      file = path.resolve('/' + decodeURIComponent(url.pathname.slice('/__e2e/fs/'.length)));
      if (!file.startsWith(os.tmpdir() + path.sep) && !file.startsWith(ROOT + path.sep)) file = null;
    } else {
      file = path.join(dist, path.normalize(decodeURIComponent(url.pathname)).replace(/^(\.\.[/\\])+/, ''));
      if (url.pathname.endsWith('/')) file = path.join(file, 'index.html');
    }
    if (!body) {
      try {
        body = fs.readFileSync(file);
      } catch {
        res.writeHead(404, { 'Cache-Control': 'no-cache' });
        res.end('not found');
        return;
      }
      if (hooks && file.endsWith(path.join(dist, 'index.html'))) {
        body = Buffer.from(String(body).replace('<head>', '<head>\n  <script src="/__e2e/hooks.js"></script>'));
      }
    }
    res.writeHead(200, { 'Content-Type': MIME[path.extname(file)] || 'application/octet-stream', 'Cache-Control': 'no-cache' });
    res.end(body);
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  return { base: `http://127.0.0.1:${server.address().port}/`, close: () => new Promise((r) => server.close(r)) };
}
