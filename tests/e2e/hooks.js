// Loaded first in index.html by the e2e server (tests/e2e/harness.mjs), never by the
// real site. A W3C WebDriver session has no console or download events in every engine
// (WebKitGTK's driver has no BiDi), so the page records them itself and the harness
// reads window.__e2e:
//   errors     console.error calls, uncaught errors, unhandled rejections, CSP
//              violations (a request off our origin) and worker `error` events;
//   downloads  files the app offers through <a download> (blob: or data: links), read
//              from the Blob the object URL was made of; the real download is
//              suppressed so no engine opens a save dialog.
(() => {
  const e2e = { errors: [], downloads: [] };
  window.__e2e = e2e;
  const text = (v) => (v && v.stack) || (v && v.message) || String(v);
  const consoleError = console.error;
  console.error = (...args) => {
    e2e.errors.push(args.map(text).join(' '));
    consoleError.apply(console, args);
  };
  addEventListener('error', (e) => e2e.errors.push('uncaught: ' + (e.message || text(e.error))));
  addEventListener('unhandledrejection', (e) => e2e.errors.push('unhandled rejection: ' + text(e.reason)));
  addEventListener('securitypolicyviolation', (e) => e2e.errors.push(`CSP blocked ${e.blockedURI} (${e.violatedDirective})`));
  const NativeWorker = window.Worker;
  window.Worker = class extends NativeWorker {
    constructor(...args) {
      super(...args);
      this.addEventListener('error', (e) => e2e.errors.push('worker: ' + (e.message || 'error event')));
    }
  };

  // The blob behind each object URL the page makes, so a download's bytes can be read
  // even after the app revokes its URL (the page's CSP forbids fetching blob: URLs).
  const blobs = new Map();
  const createObjectURL = URL.createObjectURL;
  URL.createObjectURL = function (obj) {
    const url = createObjectURL.call(URL, obj);
    if (obj instanceof Blob) blobs.set(url, obj);
    return url;
  };
  const base64 = (bytes) => {
    let bin = '';
    for (let i = 0; i < bytes.length; i += 0x8000) bin += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
    return btoa(bin);
  };
  const capture = (a) => {
    const entry = { name: a.getAttribute('download'), base64: null };
    const href = a.href;
    if (href.startsWith('data:')) {
      const comma = href.indexOf(',');
      entry.base64 = href.slice(0, comma).endsWith(';base64') ? href.slice(comma + 1) : btoa(decodeURIComponent(href.slice(comma + 1)));
      e2e.downloads.push(entry);
      return;
    }
    const blob = blobs.get(href);
    if (!blob) {
      e2e.errors.push('e2e download capture: no blob for ' + href);
      return;
    }
    blob.arrayBuffer().then((buf) => {
      entry.base64 = base64(new Uint8Array(buf));
      e2e.downloads.push(entry);
    }, (err) => e2e.errors.push('e2e download capture: ' + text(err)));
  };
  // A link the student clicks, and a detached link the app clicks itself.
  document.addEventListener('click', (e) => {
    const a = e.target instanceof Element ? e.target.closest('a[download]') : null;
    if (a) {
      e.preventDefault();
      capture(a);
    }
  }, true);
  const click = HTMLElement.prototype.click;
  HTMLElement.prototype.click = function () {
    if (this instanceof HTMLAnchorElement && this.hasAttribute('download') && !this.isConnected) {
      capture(this);
      return;
    }
    return click.call(this);
  };
})();
