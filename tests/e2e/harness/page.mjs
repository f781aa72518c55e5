// The page object: the few Playwright-like calls the suite uses, implemented over
// WebDriver the same way in every engine.
import { Key } from 'selenium-webdriver';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { sleep } from './base.mjs';

const KEYS = { Enter: Key.ENTER, ArrowLeft: Key.ARROW_LEFT, ArrowRight: Key.ARROW_RIGHT, ArrowUp: Key.ARROW_UP, ArrowDown: Key.ARROW_DOWN, Home: Key.HOME, End: Key.END, Tab: Key.TAB, Escape: Key.ESCAPE };
const q = (sel) => `document.querySelector(${JSON.stringify(sel)})`;

const sameSize = (a, b) => a[0] === b[0] && a[1] === b[1];

export class Page {
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
    const read = () => this.d.executeScript('return [innerWidth, innerHeight]');
    // The window's frame (its rect less the viewport) as last measured: with it, one resize
    // reaches the viewport asked for, instead of one to learn the frame and one to correct.
    const frame = this.windowFrame ?? { width: 0, height: 0 };
    let target = { width: width + frame.width, height: height + frame.height };
    const wanted = [width, height];
    for (let i = 0; i < 3; i++) {
      const before = await read();
      if (sameSize(before, wanted)) return;
      await win.setRect(target);
      // The page sees a resize a while after the driver answers (WebKitGTK under Xvfb; any
      // engine on a busy machine: Chromium once read 1400 px 0.5 s after asking for 390).
      // So wait until the page's viewport leaves its old size (or reaches the new one) and
      // then stops changing. The wait for the first change is capped (3 s) for a window that
      // cannot move at all, already at an engine's minimum: the only case that pays it.
      let inner = await read();
      for (let t0 = Date.now(); sameSize(inner, before) && Date.now() - t0 < 3000;) {
        await sleep(25);
        inner = await read();
      }
      for (let k = 0; k < 20; k++) {
        await sleep(25);
        const again = await read();
        if (sameSize(again, inner)) break;
        inner = again;
      }
      if (sameSize(inner, wanted)) return;
      // The window's frame is the difference between its rect and the viewport. A window
      // that cannot get there (below an engine's minimum width, above the screen) stays
      // where it got: callers read innerWidth.
      const rect = await win.getRect();
      const next = { width: rect.width + width - inner[0], height: rect.height + height - inner[1] };
      const sane = next.width >= width && next.height >= height && next.width < width + 400 && next.height < height + 400;
      if (!sane || (next.width === target.width && next.height === target.height)) return;
      this.windowFrame = { width: next.width - width, height: next.height - height };
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
