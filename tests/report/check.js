// check.js - opens femlod's HTML reports in headless Chromium (Debian's
// /usr/bin/chromium, driven by playwright-core pinned in package-lock.json)
// and checks that they rendered:
//
//   node check.js mesh PAGE.html [--screenshot OUT.png]
//     the three histograms are SVG with bars (the stretch one with 10), the
//     model-viewer element loaded the embedded GLB, and its on-screen pixels
//     are not blank (enough of them differ from the viewer's background);
//   node check.js sweep PAGE.html POINTS [--screenshot OUT.png]
//     the three scatter plots have POINTS dots each and the table POINTS rows;
//   both: no console error and no uncaught exception from the page.
//
// Exit 0 when every check passes, 1 otherwise (each failure on stderr).
'use strict';
const fs = require('fs');
const os = require('os');
const path = require('path');

const CHROMIUM = process.env.CHROMIUM || '/usr/bin/chromium';
const ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader',
  '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'];

let failures = 0;
function check(cond, what) {
  if (cond) {
    console.log('ok   ' + what);
  } else {
    console.error('FAIL ' + what);
    failures++;
  }
}

async function main() {
  const [mode, page_path, ...rest] = process.argv.slice(2);
  if (!['mesh', 'sweep'].includes(mode) || !page_path) {
    console.error('usage: node check.js mesh PAGE.html [--screenshot OUT.png] | sweep PAGE.html POINTS [--screenshot OUT.png]');
    process.exit(2);
  }
  if (!fs.existsSync(CHROMIUM)) {
    console.error(`${CHROMIUM} not found: apt-get install -y chromium`);
    process.exit(1);
  }
  let playwright;
  try {
    playwright = require('playwright-core');
  } catch (e) {
    console.error('playwright-core not installed: npm ci --prefix tests/report');
    process.exit(1);
  }
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'femlod-chromium-'));
  const context = await playwright.chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM, headless: true, args: ARGS, viewport: { width: 1360, height: 900 },
  });
  try {
    const page = context.pages()[0] || await context.newPage();
    const errors = [];
    page.on('console', (m) => { if (m.type() === 'error') errors.push('console: ' + m.text()); });
    page.on('pageerror', (e) => errors.push('exception: ' + e.message));
    // Offline: nothing may be fetched from the network.
    const requests = [];
    page.on('request', (r) => { if (!/^(file|data|blob):/.test(r.url())) requests.push(r.url()); });
    await page.goto('file://' + path.resolve(page_path), { waitUntil: 'load' });

    if (mode === 'mesh') {
      for (const id of ['stretch-histogram', 'size-histogram', 'valence-histogram']) {
        const bars = await page.$$eval(`#${id} rect.bar`, (rs) => rs.map((r) => r.getBBox().height));
        check(bars.length > 0 && bars.some((h) => h > 0), `${id}: ${bars.length} bars, some visible`);
        const box = await page.$eval(`#${id}`, (s) => { const b = s.getBoundingClientRect(); return [b.width, b.height]; });
        check(box[0] > 100 && box[1] > 100, `${id}: laid out ${box[0]} x ${box[1]}`);
      }
      const stretch = await page.$$eval('#stretch-histogram rect.bar', (rs) => rs.length);
      check(stretch === 10, `stretch histogram has 10 bins (${stretch})`);
      // model-viewer sets .loaded once the GLB is parsed; then let it render.
      await page.waitForFunction(() => {
        const v = document.querySelector('#viewer');
        return v && v.loaded === true;
      }, null, { timeout: 90000 });
      check(true, 'model-viewer loaded the embedded GLB');
      await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
      await page.waitForTimeout(1500);
      const viewer = page.locator('#viewer');
      await viewer.scrollIntoViewIfNeeded();
      const png = await viewer.screenshot();
      // Count the pixels that differ from the viewer's background (#f0f0f0),
      // decoding the screenshot in a blank page.
      const blank = await context.newPage();
      const counts = await blank.evaluate(async (b64) => {
        const img = new Image();
        img.src = 'data:image/png;base64,' + b64;
        await img.decode();
        const c = document.createElement('canvas');
        c.width = img.width;
        c.height = img.height;
        const g = c.getContext('2d');
        g.drawImage(img, 0, 0);
        const d = g.getImageData(0, 0, c.width, c.height).data;
        let differ = 0;
        const colours = new Set();
        for (let i = 0; i < d.length; i += 4) {
          const dr = Math.abs(d[i] - 240), dg = Math.abs(d[i + 1] - 240), db = Math.abs(d[i + 2] - 240);
          if (dr + dg + db > 30) differ++;
          colours.add((d[i] >> 4) * 256 + (d[i + 1] >> 4) * 16 + (d[i + 2] >> 4));
        }
        return { differ, total: d.length / 4, colours: colours.size };
      }, png.toString('base64'));
      await blank.close();
      const share = counts.differ / counts.total;
      check(share > 0.05, `viewer not blank: ${(100 * share).toFixed(1)}% of ${counts.total} pixels are the mesh`);
      check(counts.colours > 20, `viewer shows the colour map: ${counts.colours} distinct colours`);
    } else {
      const n = Number(rest[0]);
      for (const id of ['sweep-stretch-avg', 'sweep-stretch-min', 'sweep-deviation']) {
        const dots = await page.$$eval(`#${id} circle.dot`, (cs) => cs.map((c) => c.getBBox().width));
        check(dots.length === n && dots.every((w) => w > 0), `${id}: ${dots.length} dots (want ${n})`);
      }
      const rows = await page.$$eval('#points tr', (rs) => rs.length - 1);
      check(rows === n, `points table: ${rows} rows (want ${n})`);
    }
    const shot = rest.indexOf('--screenshot');
    if (shot >= 0 && rest[shot + 1]) {
      await page.screenshot({ path: rest[shot + 1], fullPage: true });
      console.log('wrote ' + rest[shot + 1]);
    }
    check(errors.length === 0, 'no console errors or exceptions' + (errors.length ? ': ' + errors.join('; ') : ''));
    check(requests.length === 0, 'works offline: no network requests' + (requests.length ? ': ' + requests.join(' ') : ''));
  } finally {
    await context.close();
    fs.rmSync(profile, { recursive: true, force: true });
  }
  if (failures) {
    console.error(`${failures} check(s) failed`);
    process.exit(1);
  }
}

main().catch((e) => {
  console.error(e && e.stack || String(e));
  process.exit(1);
});
