// End-to-end tests of the siftlab app (tests/e2e/app/, one file per view; helpers in
// common.mjs), in the engine E2E_ENGINE names, against the native CLI.
// The lab manual's examples and links into the app (URL state): each example beside
// siftlab's value, a link to the manual's Task 1 tuple, a link to frames the demo lacks.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import {
  appSuite, shot, cliRet8, BASE, page, tid, idle, tuple,
} from './common.mjs';

appSuite();

test('lab manual examples: each click shows the manual value beside siftlab\'s, equal (✓), and the intro\'s feature 132', async () => {
  await page.goto(BASE);
  await idle();
  const n = await page.count('[data-testid^="manual-example-"]');
  assert.equal(n, 8);
  for (let i = 0; i < n; i++) {
    const label = await page.textContent(tid(`manual-example-${i}`));
    const m = label.match(/get_info -a (\S+)(?: -t (\S+))? (\d+) (\d+)/);
    assert.ok(m, label);
    const [, algo, t, frame, feature] = m;
    await page.click(tid(`manual-example-${i}`));
    // The example's own pair on screen, and its comparison filled in.
    await page.waitForFunction(([cmd]) => {
      const c = document.querySelector('[data-testid="manual-compare"]');
      return c && c.textContent.includes(cmd) && document.querySelector('[data-testid="manual-mark"]');
    }, [m[0]], { timeout: 180000 });
    await idle();
    const want = cliRet8(['-a', algo, ...(t ? ['-t', t] : []), frame, feature]);
    assert.equal(await page.inputValue(tid('feature')), feature);
    assert.equal(await page.inputValue(tid('threshold')), t || '');
    assert.equal(await page.inputValue(tid('frame-id')), frame);
    assert.equal(await tuple(), want, m[0]);
    assert.equal((await page.textContent(tid('manual-got'))).trim(), want);
    assert.match(await page.getAttribute(tid(`manual-example-${i}`), 'class'), /active/);
    const expected = (await page.textContent(tid('manual-expected'))).trim();
    if (i === 0) {
      // The introduction's example: the manual's build ordered frame 100's keypoints
      // differently; OpenCV 4.8.0.76 (the CLI) gives the manual's tuple at feature 132.
      assert.equal(m[0], 'get_info -a dt -t 232.5 101 127');
      assert.notEqual(expected, want);
      assert.match(await page.textContent(tid('manual-mark')), /^≠ .*feature 127 is feature 132 here/);
      await page.click(tid('manual-other-feature'));
      await page.waitForFunction((sel) => /^✓/.test(document.querySelector(sel)?.textContent || ''), tid('manual-mark'), { timeout: 60000 });
      assert.equal(await page.inputValue(tid('feature')), '132');
      assert.equal(await tuple(), cliRet8(['-a', 'dt', '-t', '232.5', '101', '132']));
      assert.equal(await tuple(), expected, 'feature 132 is the manual\'s tuple');
      await page.screenshot(shot('manual-intro-132.png'), { fullPage: true });
    } else {
      assert.equal(expected, want, `the manual's value for ${m[0]}`);
      assert.match(await page.textContent(tid('manual-mark')), /^✓/);
    }
    if (i === 2) await page.screenshot(shot('manual-example.png'), { fullPage: true });
  }
});

test('a link to the manual\'s Task 1 tuple opens on it, with the comparison', async () => {
  await page.goto(`${BASE}?src=demo&frame=150&feature=209&algo=dt&t=300`);
  await idle();
  assert.match(await page.textContent('.slots'), /000149\.png[\s\S]*000150\.png/);
  const want = cliRet8(['-a', 'dt', '-t', '300', '150', '209']);
  assert.equal(await tuple(), want);
  assert.equal((await page.textContent(tid('manual-expected'))).trim(), want);
  assert.match(await page.textContent(tid('manual-mark')), /^✓/);
  assert.match(await page.textContent(tid('manual-compare')), /Task 1 \(dt\)/);
  assert.match(await page.url(), /\?src=demo&frame=150&feature=209&algo=dt&t=300$/);
});

test('a link to frames the demo lacks says which, and the app stays usable', async () => {
  await page.goto(`${BASE}?src=demo&frame=160&feature=5`);
  await page.waitForSelector(tid('error'));
  assert.match(await page.textContent(tid('error')),
    /FRAME_ID 160 needs frames 159 and 160: frames 159 and 160 are not in the demo, which has frames 0–150/);
  // Nothing else is shown under the link's settings, and the link stays as it was.
  assert.equal(await page.has(tid('keypoint-count-cur')), false);
  assert.equal(await page.inputValue(tid('frame-id')), '160');
  assert.match(await page.url(), /frame=160/);
  await page.screenshot(shot('missing-frame.png'));
  // One of the two missing.
  await page.goto(`${BASE}?src=demo&frame=151`);
  await page.waitForSelector(tid('error'));
  assert.match(await page.textContent(tid('error')), /FRAME_ID 151 needs frames 150 and 151: frame 151 is not in the demo, which has frames 0–150/);
  // Usable: a FRAME_ID the demo has loads, and the message goes.
  await page.fill(tid('frame-id'), '120');
  await page.press(tid('frame-id'), 'Enter');
  await page.waitForFunction(() => /000120\.png/.test(document.querySelector('.slots')?.textContent || ''), undefined, { timeout: 180000 });
  await idle();
  assert.equal(await page.has(tid('error')), false);
  assert.equal(await tuple(), cliRet8(['-a', 'nndr', '-t', '0.8', '120', await page.inputValue(tid('feature'))]));
});
