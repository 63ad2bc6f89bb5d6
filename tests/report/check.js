// check.js - opens femlod's HTML reports in headless Chromium (Debian's
// /usr/bin/chromium, driven by playwright-core pinned in package-lock.json)
// and checks that they rendered:
//
//   node check.js mesh PAGE.html [--screenshot OUT.png]
//     at 1400 x 1000: the 3D view is above the fold; the three histograms
//     are SVG with bars (the stretch one with 10, each with its count, every
//     non-empty one at least 2 px high, the threshold marked), their tick
//     labels do not overlap; the model-viewer element loaded the embedded
//     GLB, and its on-screen pixels are not blank (enough of them differ
//     from the viewer's background); the page is under 3 MB;
//   node check.js sweep PAGE.html POINTS [--screenshot OUT.png]
//     the three scatter plots have POINTS dots each and the table POINTS
//     rows; the point labels' rendered boxes do not overlap; with a second
//     grid axis, a legend whose colours are the dots' colours;
//   node check.js failed PAGE.html POINTS [--screenshot OUT.png]
//     a sweep where every point failed: the message says so, no chart, the
//     table has POINTS rows with their errors;
//   all: no console error and no uncaught exception from the page.
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
  if (!['mesh', 'sweep', 'failed'].includes(mode) || !page_path) {
    console.error('usage: node check.js mesh PAGE.html [--screenshot OUT.png] | sweep|failed PAGE.html POINTS [--screenshot OUT.png]');
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
    executablePath: CHROMIUM, headless: true, args: ARGS, viewport: { width: 1400, height: 1000 },
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

    // Boxes of elements (client rectangles) that overlap: [i, j] pairs.
    const overlaps = (boxes) => {
      const bad = [];
      for (let i = 0; i < boxes.length; i++) {
        for (let j = i + 1; j < boxes.length; j++) {
          const a = boxes[i], b = boxes[j];
          if (a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h) bad.push([a.t, b.t]);
        }
      }
      return bad;
    };
    const rects = (sel) => page.$$eval(sel, (es) => es.map((e) => {
      const r = e.getBoundingClientRect();
      return { x: r.x, y: r.y, w: r.width, h: r.height, t: e.textContent };
    }));

    if (mode === 'mesh') {
      const bytes = fs.statSync(page_path).size;
      check(bytes < 3e6, `page under 3 MB: ${(bytes / 1e6).toFixed(2)} MB`);
      const top = await page.$eval('#viewer', (v) => { const r = v.getBoundingClientRect(); return [r.top, r.bottom]; });
      check(top[1] <= 1000, `3D view above the fold at 1400 x 1000: top ${top[0]}, bottom ${top[1]}`);
      const note = await page.$$eval('#display-note', (ns) => ns.map((n) => n.textContent));
      if (note.length) console.log('     ' + note[0]);
      const ncounts = await page.$$eval('#stretch-histogram text.count', (ts) => ts.length);
      check(ncounts === 10, `a count over every stretch bar (${ncounts})`);
      const heights = await page.$$eval('#stretch-histogram rect.bar', (rs) => rs.map((r) => [r.getBBox().height,
        Number(r.querySelector('title').textContent.match(/(\d+)$/)[1])]));
      check(heights.every(([h, n]) => n === 0 || h >= 2), 'every non-empty stretch bin is a visible bar: '
        + heights.map(([h, n]) => `${n}:${h.toFixed(1)}`).join(' '));
      check(await page.$('#stretch-histogram-mark') !== null, 'the threshold is marked');
      for (const id of ['stretch-histogram', 'size-histogram', 'valence-histogram']) {
        const bad = overlaps(await rects(`#${id} text.tick`));
        check(bad.length === 0, `${id}: tick labels apart` + (bad.length ? ': ' + JSON.stringify(bad) : ''));
      }
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
    } else if (mode === 'sweep') {
      const n = Number(rest[0]);
      for (const id of ['sweep-stretch-avg', 'sweep-stretch-min', 'sweep-deviation']) {
        const dots = await page.$$eval(`#${id} circle.dot`, (cs) => cs.map((c) => c.getBBox().width));
        check(dots.length === n && dots.every((w) => w > 0), `${id}: ${dots.length} dots (want ${n})`);
      }
      const rows = await page.$$eval('#points tr', (rs) => rs.length - 1);
      check(rows === n, `points table: ${rows} rows (want ${n})`);
      for (const id of ['sweep-stretch-avg', 'sweep-stretch-min', 'sweep-deviation']) {
        const labels = await rects(`#${id} text.dotlabel`);
        const bad = overlaps(labels);
        check(labels.length > 0 && bad.length === 0, `${id}: ${labels.length} point labels, none overlapping`
          + (bad.length ? ': ' + JSON.stringify(bad) : ''));
        const ticks = overlaps(await rects(`#${id} text.tick`));
        check(ticks.length === 0, `${id}: tick labels apart`);
      }
      const fills = await page.$$eval('#sweep-stretch-avg circle.dot', (cs) => [...new Set(cs.map((c) => getComputedStyle(c).fill))]);
      const swatches = await page.$$eval('#series-legend .swatch', (ss) => ss.map((s) => getComputedStyle(s).backgroundColor));
      if (fills.length > 1) {
        check(swatches.length === fills.length && fills.every((f) => swatches.includes(f)),
          `series: ${fills.length} colours, each in the legend (${swatches.join(', ')})`);
      }
    } else {
      const n = Number(rest[0]);
      const msg = await page.$eval('#no-results', (p) => p.innerText).catch(() => '');
      check(/All \d+ points failed\./.test(msg), `the page says every point failed: "${msg}"`);
      const counts = await page.$eval('#counts', (p) => p.innerText);
      check(counts.startsWith(`${n} points: 0 ok, ${n} failed`), `counts: "${counts}"`);
      const svgs = await page.$$eval('svg.chart', (s) => s.length);
      check(svgs === 0, `no chart drawn (${svgs})`);
      const errs = await page.$$eval('#points tr', (rs) => rs.slice(1).map((r) => r.lastElementChild.textContent));
      check(errs.length === n && errs.every((e) => e.length > 0), `points table: ${errs.length} rows, each with its error`);
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
