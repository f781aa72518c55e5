// The engines' launchers: each WebDriver server and its browser session (Chromium,
// Firefox ESR, WebKitGTK), and Debian's Chromium under Playwright, all with the flags
// that keep them off this closed network.
import { Builder } from 'selenium-webdriver';
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import { sleep } from './base.mjs';
import { Page } from './page.mjs';

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
    // Without a GPU (xvfb), WebKitGTK composites its layers with OpenGL in Mesa's software
    // rasterizer (llvmpipe), whose worker threads measured 4 of the 9 CPU-s a page load took.
    // LP_NUM_THREADS=0 rasterizes on the compositor's own thread: the same pixels, 1.6 CPU-s
    // less a load (Xvfb included). WEBKIT_DISABLE_COMPOSITING_MODE, which saves all of it,
    // hangs WebDriver screenshots at some heights (4325 px of the page, not 4300 or 4400).
    env: { LP_NUM_THREADS: '0' },
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
  const proc = spawn(bin, args, { stdio: ['ignore', 'ignore', 'pipe'], env: { ...process.env, ...spec.env } });
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
