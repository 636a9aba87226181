// Browser test of a study's index.html (ctest integration.report_browser):
// Debian's headless Chromium driven by playwright-core (which downloads no
// browser) opens the page from file:// at 1440x900 and checks that
//  - the page logs no console error and raises no page error,
//  - every <img> resolves (naturalWidth > 0),
//  - the viewer switches images by key and by click,
//  - a change of exposure changes a displayed pixel value (HDR data, not PNGs),
//  - the error-map view shows a map and its colour bar,
//  - document.scrollWidth <= the window width (the page never grows wider),
//  - sorting a table by a column reorders it.
// Screenshots go to OUTDIR. usage: node report_test.js INDEX.html OUTDIR [CHROMIUM]
'use strict';
const path = require('path');
const fs = require('fs');
const { chromium } = require('playwright-core');

const [page_path, out_dir, exe = '/usr/bin/chromium'] = process.argv.slice(2);
if (!page_path || !out_dir) {
  console.error('usage: node report_test.js INDEX.html OUTDIR [CHROMIUM]');
  process.exit(2);
}
fs.mkdirSync(out_dir, { recursive: true });

const failures = [];
function check(ok, what) {
  console.log((ok ? 'ok   ' : 'FAIL ') + what);
  if (!ok) failures.push(what);
}

(async () => {
  const browser = await chromium.launch({
    executablePath: exe,
    headless: true,
    args: ['--no-sandbox', '--allow-file-access-from-files', '--disable-gpu'],
  });
  const page = await browser.newPage({ viewport: { width: 1440, height: 900 } });
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push('console: ' + m.text()); });
  page.on('pageerror', (e) => errors.push('page error: ' + e.message));
  page.on('requestfailed', (r) => errors.push('request failed: ' + r.url()));
  await page.goto('file://' + path.resolve(page_path), { waitUntil: 'load' });
  // the viewer loads its HDR scripts after the page: let them come
  await page.waitForFunction(() => {
    const v = window.gibViewers && window.gibViewers[0];
    return v && v.hasHdr(v.a) && v.hasHdr(v.b);
  }, null, { timeout: 15000 }).catch(() => {});
  await page.screenshot({ path: path.join(out_dir, 'page_top.png') });
  await page.screenshot({ path: path.join(out_dir, 'page_full.png'), fullPage: true });

  const imgs = await page.$$eval('img', (l) => l.map((i) => ({ src: i.getAttribute('src'), w: i.naturalWidth })));
  check(imgs.length > 0, `the page has images (${imgs.length})`);
  const broken = imgs.filter((i) => !(i.w > 0));
  check(broken.length === 0, 'every <img> resolves' + (broken.length ? ': ' + broken.map((i) => i.src).join(' ') : ''));

  const width = await page.evaluate(() => ({ doc: document.documentElement.scrollWidth, body: document.body.scrollWidth, win: window.innerWidth }));
  check(width.doc <= width.win && width.body <= width.win,
        `page width ${width.doc} px (body ${width.body}) within the window's ${width.win} px`);
  fs.writeFileSync(path.join(out_dir, 'page_width.txt'), `${width.doc}\n`);
  // no element reaches past the window, except inside a box that scrolls
  const wide = await page.evaluate(() => {
    const out = [];
    for (const e of document.body.querySelectorAll('*')) {
      if (e.closest('.scroll')) continue;
      const r = e.getBoundingClientRect();
      if (r.width && r.right > window.innerWidth + 0.5) out.push(e.tagName + '.' + e.className + ' ' + Math.round(r.right));
    }
    return out;
  });
  check(wide.length === 0, 'no element past the window\'s right edge' + (wide.length ? ': ' + wide.slice(0, 5).join(', ') : ''));

  const nviewers = await page.evaluate(() => (window.gibViewers || []).length);
  check(nviewers >= 1, `${nviewers} image viewer(s)`);
  if (nviewers >= 1) {
    const state = () => page.evaluate(() => {
      const v = window.gibViewers[0];
      return { a: v.a, b: v.b, n: v.set.images.length, cap: v.caps[0].textContent, readout: v.readout.textContent,
               view: v.view, hdr: v.hasHdr(v.a) };
    });
    const s0 = await state();
    check(s0.n >= 3, `the viewer lists ${s0.n} images (references and runs)`);
    check(s0.hdr, 'the shown image has its HDR data');
    // key: next image
    const box = await page.locator('.gib-viewer').first().boundingBox();
    await page.mouse.move(box.x + 20, box.y + 5);
    await page.keyboard.press('ArrowRight');
    const s1 = await state();
    check(s1.a === (s0.a + 1) % s0.n && s1.cap !== s0.cap, `ArrowRight switches the image (${s0.a} -> ${s1.a})`);
    // click: the last image's button
    await page.locator('.gib-viewer').first().locator('.gib-list button').nth(s0.n - 1).click();
    const s2 = await state();
    check(s2.a === s0.n - 1, `a click picks image ${s0.n - 1} (now ${s2.a})`);
    await page.waitForFunction(() => { const v = window.gibViewers[0]; return v.hasHdr(v.a); }, null, { timeout: 10000 })
      .catch(() => {});
    // exposure: the displayed value of the pixel at the canvas centre
    const canvas = page.locator('.gib-viewer').first().locator('canvas.gib-canvas').first();
    const cb = await canvas.boundingBox();
    await page.mouse.move(cb.x + cb.width / 2, cb.y + cb.height / 2);
    const r0 = (await state()).readout;
    const px = () => canvas.evaluate((c) => {
      const d = c.getContext('2d').getImageData(Math.floor(c.width / 2), Math.floor(c.height / 2), 1, 1).data;
      return [d[0], d[1], d[2]];
    });
    const p0 = await px();
    await page.evaluate(() => window.gibViewers[0].setEv(window.gibViewers[0].ev + 2));
    await page.mouse.move(cb.x + cb.width / 2 + 1, cb.y + cb.height / 2);
    await page.mouse.move(cb.x + cb.width / 2, cb.y + cb.height / 2);
    const r1 = (await state()).readout;
    const p1 = await px();
    check(/shown \d+ \d+ \d+/.test(r0) && /linear/.test(r0), `pixel readout: ${r0}`);
    check(r0 !== r1, `exposure +2 EV changes the displayed value: ${r1}`);
    check(p0.join() !== p1.join(), `exposure +2 EV changes the canvas pixel ${p0} -> ${p1}`);
    await page.locator('.gib-viewer').first().screenshot({ path: path.join(out_dir, 'viewer_exposure.png') });
    // key: the error map, with its colour bar
    await page.keyboard.press('m');
    const s3 = await state();
    check(s3.view !== 'image', `m shows the error map (${s3.view})`);
    await page.waitForTimeout(300);
    const bar = await page.evaluate(() => {
      const c = window.gibViewers[0].colorbar;
      return c.style.display !== 'none' ? c.height : 0;
    });
    check(bar >= 128, `the colour bar is drawn ${bar} px tall`);
    await page.locator('.gib-viewer').first().screenshot({ path: path.join(out_dir, 'viewer_error_map.png') });
    const maps = await page.evaluate(() => { const v = window.gibViewers[0]; return (v.image(v.a).maps || []).map((m) => m.name); });
    check(maps.includes('relative error') && maps.includes('FLIP'), `error maps of the run: ${maps.join(', ')}`);
    await page.keyboard.press('m');
    const s4 = await state();
    check(s4.view === 'FLIP', `m again shows ${s4.view}`);
    await page.waitForTimeout(300);
    await page.locator('.gib-viewer').first().screenshot({ path: path.join(out_dir, 'viewer_flip_map.png') });
    // modes
    for (const [k, mode] of [['s', 'side'], ['w', 'wipe'], ['f', 'flip']]) {
      await page.keyboard.press(k);
      const m = await page.evaluate(() => window.gibViewers[0].mode);
      check(m === mode, `key ${k}: mode ${m}`);
      await page.locator('.gib-viewer').first().screenshot({ path: path.join(out_dir, `viewer_${mode}.png`) });
    }
    const w2 = await page.evaluate(() => document.documentElement.scrollWidth);
    check(w2 <= 1440, `page width ${w2} px after the viewer modes`);
  }

  // sorting: a numeric column of the runs table
  const sorted = await page.evaluate(() => {
    const t = document.querySelector('#runs + p + .scroll table');
    if (!t) return null;
    const th = t.tHead.rows[0].cells[7]; // relMSE full
    th.click();
    const v = Array.from(t.tBodies[0].rows).map((r) => parseFloat(r.cells[7].getAttribute('data-v')))
      .filter((x) => !isNaN(x));
    return v.every((x, i) => i === 0 || v[i - 1] <= x) ? v.length : -1;
  });
  check(sorted !== null && sorted > 0, `the runs table sorts by relMSE (${sorted} rows)`);

  check(errors.length === 0, 'no console or page error' + (errors.length ? ': ' + errors.join('; ') : ''));
  await browser.close();
  console.log(failures.length ? `${failures.length} check(s) failed` : 'all checks passed');
  process.exit(failures.length ? 1 : 0);
})().catch((e) => { console.error('report_test: ' + e.message); process.exit(1); });
