// One harness for the three engines a student's browser runs on: Chromium (Debian's
// chromium + chromedriver), Firefox ESR (geckodriver) and WebKitGTK, Safari's engine
// (WebKitWebDriver + MiniBrowser under an X display). Each is driven over the W3C
// WebDriver protocol by selenium-webdriver; the page object below offers the few
// Playwright-like calls the suite uses, implemented the same way in every engine.
//
// The harness serves dist/ itself (same MIME types and no-cache as www/serve.py) so that
// it can put tests/e2e/hooks.js first in index.html: WebDriver classic has no console or
// download events, so the page records them (see hooks.js). It also serves local test
// folders under /__e2e/fs/ so that a folder can be handed to the page in engines whose
// driver cannot upload a directory (WebKitWebDriver sends a directory as an empty file).
import { Builder, Key } from 'selenium-webdriver';
import assert from 'node:assert/strict';
import { before, after, beforeEach, afterEach } from 'node:test';
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const HERE = path.dirname(fileURLToPath(import.meta.url));
export const ROOT = path.resolve(HERE, '../..');

const MIME = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript', '.mjs': 'text/javascript',
  '.wasm': 'application/wasm', '.css': 'text/css', '.svg': 'image/svg+xml', '.png': 'image/png',
  '.jpg': 'image/jpeg', '.txt': 'text/plain; charset=utf-8', '.md': 'text/markdown; charset=utf-8',
  '.json': 'application/json',
};
const HOOKS = fs.readFileSync(path.join(HERE, 'hooks.js'));

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

async function freePort() {
  const s = net.createServer();
  await new Promise((r) => s.listen(0, '127.0.0.1', r));
  const { port } = s.address();
  await new Promise((r) => s.close(r));
  return port;
}

const which = (cands) => cands.find((c) => fs.existsSync(c));
const GECKODRIVER = () => which([process.env.GECKODRIVER, path.join(os.homedir(), '.cargo/bin/geckodriver'), '/usr/local/bin/geckodriver', '/usr/bin/geckodriver'].filter(Boolean));
const MINIBROWSER = () => which([process.env.MINIBROWSER, '/usr/lib/x86_64-linux-gnu/webkit2gtk-4.1/MiniBrowser', '/usr/lib/aarch64-linux-gnu/webkit2gtk-4.1/MiniBrowser', '/usr/libexec/webkit2gtk-4.1/MiniBrowser'].filter(Boolean));

// The flags keep Chromium off this closed network (it would try Google's hosts): every
// script that starts Chromium starts it with these (WebDriver here, Playwright through
// launchChromium), so none drifts.
export const CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--no-first-run',
  '--disable-component-update', '--disable-sync', '--disable-quic'];

/** Debian's Chromium (or $CHROMIUM) under Playwright, with CHROMIUM_ARGS and `extra`. */
export async function launchChromium(extra = []) {
  const { chromium } = await import('playwright-core');
  return chromium.launch({ executablePath: process.env.CHROMIUM || '/usr/bin/chromium', args: [...CHROMIUM_ARGS, ...extra] });
}

export const ENGINES = {
  chromium: {
    driver: (port) => [process.env.CHROMEDRIVER || '/usr/bin/chromedriver', [`--port=${port}`]],
    caps: () => ({ browserName: 'chrome', 'goog:chromeOptions': { binary: process.env.CHROMIUM || '/usr/bin/chromium', args: CHROMIUM_ARGS } }),
    canUploadFolder: true,
  },
  firefox: {
    driver: (port) => [GECKODRIVER(), ['--port', String(port), '--log', 'error']],
    caps: () => ({
      browserName: 'firefox',
      'moz:firefoxOptions': {
        binary: process.env.FIREFOX || '/usr/bin/firefox-esr',
        args: ['-headless'],
        // Nothing to look up on this closed network.
        prefs: { 'app.update.enabled': false, 'network.captive-portal-service.enabled': false, 'browser.safebrowsing.malware.enabled': false,
          'browser.safebrowsing.phishing.enabled': false, 'datareporting.policy.dataSubmissionEnabled': false, 'toolkit.telemetry.enabled': false },
      },
    }),
    // geckodriver answers a folder with "File not found".
    canUploadFolder: false,
  },
  webkit: {
    driver: (port) => ['/usr/bin/WebKitWebDriver', [`--port=${port}`]],
    // MiniBrowser needs --automation to accept a WebDriver session, and an X display
    // (tests/e2e/run.sh starts the suite under xvfb-run).
    caps: () => ({ browserName: 'MiniBrowser', 'webkitgtk:browserOptions': { binary: MINIBROWSER(), args: ['--automation'] } }),
    canUploadFolder: false,
  },
};

/** Starts `engine`'s driver and one browser session; returns a Browser. */
export async function launch(engine) {
  const spec = ENGINES[engine];
  if (!spec) throw new Error(`unknown engine ${engine}: use one of ${Object.keys(ENGINES).join(', ')}`);
  const port = await freePort();
  const [bin, args] = spec.driver(port);
  if (!bin || !fs.existsSync(bin)) throw new Error(`${engine}: driver ${bin} is missing: run tests/setup`);
  const proc = spawn(bin, args, { stdio: ['ignore', 'ignore', 'pipe'] });
  let stderr = '';
  proc.stderr.on('data', (d) => { stderr += d; });
  for (let i = 0; ; i++) {
    try {
      await fetch(`http://127.0.0.1:${port}/status`);
      break;
    } catch (e) {
      if (i > 100) throw new Error(`${engine}: driver did not start: ${stderr}`);
      await sleep(100);
    }
  }
  const driver = await new Builder().usingServer(`http://127.0.0.1:${port}`).withCapabilities(spec.caps()).build();
  await driver.manage().setTimeouts({ script: 900000, pageLoad: 120000, implicit: 0 });
  const caps = await driver.getCapabilities();
  return new Browser(engine, driver, proc, caps.get('browserVersion'));
}

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

/**
 * Registers a test file's hooks: dist/ served and one `engine` session for the file
 * (`onStart({ base, browser })`), a fresh 1400×900 page for each case (`onPage(page)`),
 * and after each case the checks every case shares: no resource fetched off our origin,
 * no error recorded by the page or its workers. `onEnd` runs once, after the last case.
 */
export function suite(engine, { onStart = () => {}, onPage, onEnd = () => {} }) {
  let server;
  let browser;
  let page;
  before(async () => {
    server = await serve(path.join(ROOT, 'dist'));
    browser = await launch(engine);
    await onStart({ base: server.base, browser });
  });
  after(async () => {
    await browser?.close();
    await server?.close();
    await onEnd();
  });
  beforeEach(async () => {
    page = await browser.newPage({ width: 1400, height: 900 });
    onPage(page);
  });
  afterEach(async () => {
    assert.deepEqual(await page.offOrigin(), [], 'requests left the origin');
    assert.deepEqual(await page.flushErrors(), [], 'console errors');
  });
}

class Browser {
  constructor(engine, driver, proc, version) {
    Object.assign(this, { engine, driver, proc, version });
    this.canUploadFolder = ENGINES[engine].canUploadFolder;
  }
  /** A fresh page: about:blank at the given viewport, downloads cleared. */
  async newPage({ width = 1400, height = 900 } = {}) {
    const page = new Page(this);
    await this.driver.get('about:blank');
    await page.setViewportSize({ width, height });
    return page;
  }
  async close() {
    try {
      await this.driver.quit();
    } finally {
      this.proc.kill();
    }
  }
}

const KEYS = { Enter: Key.ENTER, ArrowLeft: Key.ARROW_LEFT, ArrowRight: Key.ARROW_RIGHT, ArrowUp: Key.ARROW_UP, ArrowDown: Key.ARROW_DOWN, Home: Key.HOME, End: Key.END, Tab: Key.TAB, Escape: Key.ESCAPE };
const q = (sel) => `document.querySelector(${JSON.stringify(sel)})`;

class Page {
  constructor(browser) {
    this.browser = browser;
    this.d = browser.driver;
    this.seenErrors = 0;
    this.errors = [];
  }

  async goto(url) {
    await this.flushErrors();
    await this.d.get(url);
    this.seenErrors = 0;
  }
  async url() {
    return this.d.getCurrentUrl();
  }

  /** Runs `fn(arg)` in the page (it may be async) and returns its JSON result. */
  async evaluate(fn, arg) {
    const r = await this.d.executeAsyncScript(
      `const done = arguments[arguments.length - 1];
       try { Promise.resolve((${fn})(arguments[0])).then((v) => done({ ok: v === undefined ? null : v }), (e) => done({ err: String(e) + (e && e.stack ? " at " + e.stack : "") })); }
       catch (e) { done({ err: String(e) + (e && e.stack ? " at " + e.stack : "") }); }`, arg === undefined ? null : arg);
    if (r.err) throw new Error(`in the page: ${r.err}`);
    return r.ok;
  }

  /** Runs a script's source in the page as it is (a library such as axe-core). */
  async injectScript(source) {
    await this.d.executeScript(`${source}\n;return true;`);
  }

  /** Polls `fn(arg)` in the page until it is truthy; returns that value. */
  async waitForFunction(fn, arg, { timeout = 30000, what } = {}) {
    const end = Date.now() + timeout;
    for (;;) {
      const v = await this.evaluate(fn, arg);
      if (v) return v;
      if (Date.now() > end) throw new Error(`timed out after ${timeout} ms waiting for ${what || fn}`);
      await sleep(100);
    }
  }

  /** Waits for `sel` to be visible (state 'visible'), present ('attached') or gone ('detached'). */
  async waitForSelector(sel, { state = 'visible', timeout = 30000 } = {}) {
    return this.waitForFunction(([s, st]) => {
      const el = document.querySelector(s);
      if (st === 'detached') return !el;
      if (st === 'attached') return !!el;
      return !!el && el.getClientRects().length > 0 && getComputedStyle(el).visibility !== 'hidden';
    }, [sel, state], { timeout, what: `${sel} ${state}` });
  }

  async has(sel) {
    return this.evaluate((s) => !!document.querySelector(s), sel);
  }
  async count(sel) {
    return this.evaluate((s) => document.querySelectorAll(s).length, sel);
  }
  async textContent(sel) {
    await this.waitForSelector(sel, { state: 'attached' });
    return this.evaluate((s) => document.querySelector(s).textContent, sel);
  }
  async inputValue(sel) {
    await this.waitForSelector(sel, { state: 'attached' });
    return this.evaluate((s) => document.querySelector(s).value, sel);
  }
  async getAttribute(sel, name) {
    await this.waitForSelector(sel, { state: 'attached' });
    return this.evaluate(([s, n]) => document.querySelector(s).getAttribute(n), [sel, name]);
  }
  async innerHTML(sel) {
    await this.waitForSelector(sel, { state: 'attached' });
    return this.evaluate((s) => document.querySelector(s).innerHTML, sel);
  }
  /** `fn` mapped over every match of `sel`, in the page. */
  async evalAll(sel, fn) {
    // Spliced into the script's source: the page's CSP forbids eval() (WebKit enforces it on
    // the driver's scripts too).
    return this.evaluate(`(s) => [...document.querySelectorAll(s)].map(${fn})`, sel);
  }

  async element(sel) {
    await this.waitForSelector(sel);
    return this.d.executeScript(`return ${q(sel)}`);
  }
  /** A real click (the driver's pointer), scrolled into view first. */
  async click(sel) {
    const el = await this.element(sel);
    await this.d.executeScript('arguments[0].scrollIntoView({ block: "center" })', el);
    await el.click();
  }
  async check(sel) {
    if (!(await this.evaluate((s) => document.querySelector(s).checked, sel))) await this.click(sel);
  }
  /** Sets an input's value as typing would leave it and fires `input` (what the app listens to). */
  async fill(sel, value) {
    await this.waitForSelector(sel);
    await this.evaluate(([s, v]) => {
      const el = document.querySelector(s);
      el.focus();
      const proto = el instanceof HTMLTextAreaElement ? HTMLTextAreaElement.prototype : HTMLInputElement.prototype;
      Object.getOwnPropertyDescriptor(proto, 'value').set.call(el, v);
      el.dispatchEvent(new Event('input', { bubbles: true }));
    }, [sel, String(value)]);
  }
  /** Enter in a field commits it: the `change` event, then the form's implicit submission. */
  async press(sel, key) {
    const el = await this.element(sel);
    if (key === 'Enter') {
      // The value was set by fill() (no typing), so an engine may not see it as changed;
      // fire `change` as committing a typed value does, then press the real key.
      await this.d.executeScript('arguments[0].dispatchEvent(new Event("change", { bubbles: true }))', el);
    }
    await el.sendKeys(KEYS[key] || key);
  }
  async selectOption(sel, value) {
    await this.waitForSelector(sel);
    await this.evaluate(([s, v]) => {
      const el = document.querySelector(s);
      if (![...el.options].some((o) => o.value === v)) throw new Error(`${s} has no option ${v}`);
      el.value = v;
      el.dispatchEvent(new Event('input', { bubbles: true }));
      el.dispatchEvent(new Event('change', { bubbles: true }));
    }, [sel, value]);
  }
  async focus(sel) {
    await this.waitForSelector(sel);
    await this.evaluate((s) => document.querySelector(s).focus(), sel);
  }
  /** A key pressed on whatever has the focus. */
  async keyboard(key) {
    const k = KEYS[key] || key;
    await this.d.actions({ async: true }).keyDown(k).keyUp(k).perform();
  }
  /** The element's box in viewport pixels, after scrolling it into view. */
  async boundingBox(sel) {
    await this.waitForSelector(sel);
    return this.evaluate((s) => {
      const el = document.querySelector(s);
      el.scrollIntoView({ block: 'nearest' });
      const r = el.getBoundingClientRect();
      return { x: r.x, y: r.y, width: r.width, height: r.height };
    }, sel);
  }
  async mouseMove(x, y) {
    await this.d.actions({ async: true }).move({ x: Math.round(x), y: Math.round(y), origin: 'viewport' }).perform();
  }
  async mouseClick(x, y) {
    await this.d.actions({ async: true }).move({ x: Math.round(x), y: Math.round(y), origin: 'viewport' }).click().perform();
  }

  /** Sets the viewport (not the window) to width × height CSS pixels. */
  async setViewportSize({ width, height }) {
    const win = this.d.manage().window();
    let target = { width, height };
    for (let i = 0; i < 3; i++) {
      await win.setRect(target);
      // The page sees a resize a little after the driver answers (WebKitGTK under Xvfb
      // especially): read the viewport once it has stopped changing.
      let inner = await this.d.executeScript('return [innerWidth, innerHeight]');
      for (let k = 0; k < 20; k++) {
        await sleep(25);
        const again = await this.d.executeScript('return [innerWidth, innerHeight]');
        if (again[0] === inner[0] && again[1] === inner[1]) break;
        inner = again;
      }
      if (inner[0] === width && inner[1] === height) return;
      // The window's frame is the difference between its rect and the viewport. A window
      // that cannot get there (below an engine's minimum width, above the screen) stays
      // where it got: callers read innerWidth.
      const rect = await win.getRect();
      const next = { width: rect.width + width - inner[0], height: rect.height + height - inner[1] };
      const sane = next.width >= width && next.height >= height && next.width < width + 400 && next.height < height + 400;
      if (!sane || (next.width === target.width && next.height === target.height)) return;
      target = next;
    }
  }

  /**
   * Runs `fn` with the viewport at least `height` tall: drivers capture only what is in
   * the viewport. A window cannot outgrow its screen (WebKitGTK under Xvfb refuses the
   * size), so the height stops there, and then what is visible is captured.
   */
  async withHeight(height, fn) {
    const [w, h, screenH] = await this.d.executeScript('return [innerWidth, innerHeight, screen.height]');
    if (height <= h) return fn();
    const restore = { width: w, height: h };
    try {
      await this.setViewportSize({ width: w, height: Math.min(height, 6000, Math.max(h, screenH - 100)) });
    } catch {
      await this.setViewportSize(restore);
    }
    try {
      return await fn();
    } finally {
      await this.setViewportSize(restore);
    }
  }

  async screenshot(file, { fullPage = false } = {}) {
    const height = fullPage ? await this.d.executeScript('return document.documentElement.scrollHeight') : 0;
    const shot = await this.withHeight(height, () => this.d.takeScreenshot());
    fs.writeFileSync(file, Buffer.from(shot, 'base64'));
  }
  async elementScreenshot(sel, file) {
    const el = await this.element(sel);
    const height = await this.d.executeScript('return Math.ceil(arguments[0].getBoundingClientRect().height) + 20', el);
    const shot = await this.withHeight(height, async () => {
      await this.d.executeScript('arguments[0].scrollIntoView({ block: "start" })', el);
      // WebKitWebDriver's element screenshot takes the wrong region of a scrolled page
      // (the page's top, part of it black): there the viewport, scrolled to the element.
      return this.browser.engine === 'webkit' ? this.d.takeScreenshot() : el.takeScreenshot();
    });
    fs.writeFileSync(file, Buffer.from(shot, 'base64'));
  }

  /**
   * Gives the page files through `<input type=file>` `sel`: a path (file or, with
   * `webkitdirectory`, a folder) or {name, mimeType, buffer}. Where the engine's driver
   * cannot upload a folder, the page builds the same FileList itself from the folder's
   * files served under /__e2e/fs/, with each file's webkitRelativePath as a picker sets it.
   */
  async setInputFiles(sel, what) {
    const el = await this.element(sel);
    let file = what;
    if (typeof what !== 'string') {
      const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-e2e-upload-'));
      file = path.join(dir, what.name);
      fs.writeFileSync(file, what.buffer);
    }
    if (!fs.statSync(file).isDirectory() || this.browser.canUploadFolder) {
      // A new pick replaces the old one; ChromeDriver would add to a `multiple` input's list.
      await this.d.executeScript('arguments[0].value = ""', el);
      await el.sendKeys(file);
      return;
    }
    const base = path.basename(file);
    const list = walk(file).map((f) => ({ url: '/__e2e/fs' + f, rel: base + '/' + path.relative(file, f).split(path.sep).join('/') }));
    await this.evaluate(async ([s, files]) => {
      // A File made in the page has an empty webkitRelativePath, and an own property on it
      // does not survive (WebKit may hand the FileList's files out as new wrappers). So
      // each file gets a unique lastModified stamp, and the getter answers by that stamp.
      if (!window.__e2eRel) {
        window.__e2eRel = new Map();
        window.__e2eStamp = 1e12;
        const native = Object.getOwnPropertyDescriptor(File.prototype, 'webkitRelativePath');
        Object.defineProperty(File.prototype, 'webkitRelativePath', {
          configurable: true,
          get() { return window.__e2eRel.get(this.lastModified) ?? native.get.call(this); },
        });
      }
      const dt = new DataTransfer();
      for (const f of files) {
        const blob = await (await fetch(f.url)).blob();
        const stamp = window.__e2eStamp++;
        window.__e2eRel.set(stamp, f.rel);
        dt.items.add(new File([blob], f.rel.split('/').pop(), { type: blob.type, lastModified: stamp }));
      }
      const input = document.querySelector(s);
      input.files = dt.files;
      if (input.files.length !== files.length || (files.length && input.files[0].webkitRelativePath !== files[0].rel)) {
        throw new Error('the FileList lost files or their relative paths');
      }
      input.dispatchEvent(new Event('change', { bubbles: true }));
    }, [sel, list]);
  }

  /** Drops a file (served from a local path) onto `sel` as a drag and drop would. */
  async dropFile(sel, file, mimeType = 'image/png') {
    await this.waitForSelector(sel);
    await this.evaluate(async ([s, url, name, type]) => {
      const blob = await (await fetch(url)).blob();
      const dt = new DataTransfer();
      dt.items.add(new File([blob], name, { type }));
      const el = document.querySelector(s);
      for (const t of ['dragenter', 'dragover', 'drop']) {
        el.dispatchEvent(new DragEvent(t, { bubbles: true, cancelable: true, dataTransfer: dt }));
      }
    }, [sel, '/__e2e/fs' + file, path.basename(file), mimeType]);
  }

  /** Waits for the next download the page offers after `action`; returns {name, bytes}. */
  async download(action, { timeout = 60000 } = {}) {
    const before = await this.evaluate(() => window.__e2e.downloads.length);
    await action();
    try {
      await this.waitForFunction((n) => window.__e2e.downloads.length > n, before, { timeout, what: 'a download' });
    } catch (e) {
      throw new Error(`${e.message}; the page's errors: ${JSON.stringify(await this.flushErrors())}`);
    }
    const d = await this.evaluate((n) => window.__e2e.downloads[n], before);
    return { name: d.name, bytes: Buffer.from(d.base64, 'base64') };
  }

  /** Moves the errors the document recorded (hooks.js) into this.errors. */
  async flushErrors() {
    const all = await this.evaluate(() => (window.__e2e ? window.__e2e.errors : []));
    this.errors.push(...all.slice(this.seenErrors));
    this.seenErrors = all.length;
    return this.errors;
  }
  /** Resources the page fetched from another origin (the Resource Timing list). */
  async offOrigin() {
    return this.evaluate(() => performance.getEntriesByType('resource').map((e) => e.name)
      .filter((u) => !u.startsWith('data:') && !u.startsWith('blob:') && new URL(u).origin !== location.origin));
  }
}

function walk(dir) {
  return fs.readdirSync(dir, { withFileTypes: true }).flatMap((e) => {
    const p = path.join(dir, e.name);
    return e.isDirectory() ? walk(p) : [p];
  });
}
