// Opens scanlod report pages in headless Chromium (playwright-core, Debian's chromium)
// and checks what a visitor would see (tests/export/test_html_report.sh):
//   node scripts/viewer/check_page.mjs [--http ROOT] [--shots DIR] [--levels]
//                                      [--max-first-draw MS] PAGE.html...
// Per page: every view (figure.sl-view) is scrolled into sight (a data-load="click" view
// is clicked) and must reach data-state "drawn" with its canvas showing the model (pixels
// opaque and not the background colour); at no time may more than one view be live
// (drawn); before any view is chosen the page may have asked for at most one GLB script
// (the first level of its one auto-loading view: not every level up front); the console
// must stay free of errors and the page of exceptions; and no request may leave the
// page's own files: file://, or with --http ROOT the pages are served from ROOT by a
// server on 127.0.0.1 and only that server, blob: and data: URLs are allowed (anything
// else is aborted and reported). --levels also clicks every level button of every view
// and checks each level draws. --max-first-draw: the page's first view must have drawn
// within MS milliseconds of the page's start (its data-drawn-ms). --shots writes a
// full-page screenshot per page (DIR/<page name>.png). SCANLOD_VIEW_TIMEOUT_MS: how long a
// view may take to draw (default 60 s); SCANLOD_CHROMIUM: the browser (default: chromium
// on PATH).
// Prints one JSON line per view ({in: page URL, src: its .glb.js, state, triangles, drawn:
// share of the canvas, morph: the morph weight drawn or null, live: views drawn at once}),
// one per page with what a visitor reads ({page, url, views, errors, first_draw_ms,
// glb_scripts_before_choice, head: {title, ids, credit, frame, description} as shown,
// "" when hidden, cards: [{src, text, visible}] per level card}); exits 1 if anything
// failed, 2 on usage.
import { createServer } from 'node:http';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, statSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { delimiter, extname, join, relative, resolve, sep } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

const BACKGROUND = [240, 240, 240]; // viewer.js: sRGB 0.94, as the thumbnails
const MIN_DRAWN = 0.01;              // share of the canvas that must show the model
const TIMEOUT_MS = Number(process.env.SCANLOD_VIEW_TIMEOUT_MS) || 60000; // per view

function usage() {
  console.error('usage: check_page.mjs [--http ROOT] [--shots DIR] [--levels] PAGE.html...');
  process.exit(2);
}

const args = process.argv.slice(2);
let httpRoot = null, shots = null, levels = false, maxFirstDraw = 0;
const pages = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--http') httpRoot = resolve(args[++i] || usage());
  else if (args[i] === '--max-first-draw') maxFirstDraw = Number(args[++i]) || usage();
  else if (args[i] === '--shots') shots = resolve(args[++i] || usage());
  else if (args[i] === '--levels') levels = true;
  else if (args[i].startsWith('--')) usage();
  else pages.push(resolve(args[i]));
}
if (!pages.length) usage();

function findChromium() {
  if (process.env.SCANLOD_CHROMIUM) return process.env.SCANLOD_CHROMIUM;
  for (const dir of (process.env.PATH || '').split(delimiter))
    for (const name of ['chromium', 'chromium-browser']) {
      const p = join(dir, name);
      if (existsSync(p)) return p;
    }
  console.error('check_page: no chromium on PATH (Debian package chromium: scripts/install-deps.sh)');
  process.exit(2);
}

const TYPES = { '.html': 'text/html; charset=utf-8', '.js': 'text/javascript', '.json': 'application/json',
  '.png': 'image/png', '.glb': 'model/gltf-binary', '.md': 'text/markdown' };

// A static file server for ROOT on 127.0.0.1 (an ephemeral port).
function serve(root) {
  const server = createServer((req, res) => {
    const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    const file = join(root, path);
    if (!file.startsWith(root + sep) || !existsSync(file) || !statSync(file).isFile()) {
      res.writeHead(404);
      res.end();
      return;
    }
    res.writeHead(200, { 'content-type': TYPES[extname(file)] || 'application/octet-stream' });
    res.end(readFileSync(file));
  });
  return new Promise((ok) => server.listen(0, '127.0.0.1', () => ok(server)));
}

let failed = 0;
function fail(what) {
  failed++;
  console.log(JSON.stringify({ fail: what }));
}

// The share of the canvas that is opaque and differs from the background.
async function drawnShare(figure) {
  return figure.evaluate((f, bg) => {
    const c = f.querySelector('canvas');
    if (!c.width || !c.height) return 0;
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4)
      if (d[i + 3] === 255 && (Math.abs(d[i] - bg[0]) > 12 || Math.abs(d[i + 1] - bg[1]) > 12 ||
                               Math.abs(d[i + 2] - bg[2]) > 12)) n++;
    return n / (c.width * c.height);
  }, BACKGROUND);
}

async function waitDrawn(page, figure, url, src) {
  const what = `${url} ${src}`;
  try {
    await page.waitForFunction((f) => f.dataset.state === 'drawn' || f.dataset.state === 'error',
                               await figure.elementHandle(), { timeout: TIMEOUT_MS });
  } catch (e) { /* reported below as the state it is stuck in */ }
  const state = (await figure.getAttribute('data-state')) || 'none';
  const triangles = Number(await figure.getAttribute('data-triangles'));
  const share = await drawnShare(figure);
  const morph = await figure.getAttribute('data-morph'); // the morph weight drawn, if any
  const live = await page.locator('figure.sl-view[data-state="drawn"]').count();
  const row = { in: url, src, state, triangles, drawn: Number(share.toFixed(4)), morph, live };
  console.log(JSON.stringify(row));
  if (state !== 'drawn') fail(`${what}: state ${state}`);
  else if (share < MIN_DRAWN) fail(`${what}: the canvas shows no model (${(100 * share).toFixed(2)} % drawn)`);
  if (live > 1) fail(`${what}: ${live} views live at once (one per page)`);
  return row;
}

// What a visitor reads: the item's heading, ids, credit, frame note, description, and each
// level card's text, as rendered ("" when not visible).
async function readable(page) {
  const shown = async (sel) => {
    const l = page.locator(sel).first();
    return (await l.count()) && (await l.isVisible()) ? (await l.innerText()).trim() : '';
  };
  const head = { title: await shown('section.item h1, section.item h2'), ids: await shown('.ids'),
    credit: await shown('.credit'), frame: await shown('.frame'), description: await shown('.description') };
  const cards = [];
  const all = page.locator('.level');
  for (let i = 0; i < await all.count(); i++) {
    const c = all.nth(i);
    const img = c.locator('img');
    cards.push({ src: (await c.getAttribute('data-src')) || ((await img.count()) ? await img.getAttribute('src') : ''),
      text: (await c.innerText()).replace(/\s+/g, ' ').trim(), visible: await c.isVisible() });
  }
  return { head, cards };
}

async function checkPage(context, url, name) {
  const page = await context.newPage();
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push('console error: ' + m.text().slice(0, 300)); });
  page.on('pageerror', (e) => errors.push('page error: ' + String(e).slice(0, 300)));
  const glbScripts = [];
  page.on('request', (r) => { if (r.url().endsWith('.glb.js')) glbScripts.push(r.url()); });
  await page.setViewportSize({ width: 1280, height: 900 });
  await page.goto(url, { waitUntil: 'load' });
  const figures = page.locator('figure.sl-view');
  const count = await figures.count();
  // Before any choice: the auto-loading view (if any) has drawn, or had its chance to.
  const auto = page.locator('figure.sl-view:not([data-load="click"])');
  if (await auto.count())
    await page.waitForFunction((f) => f.dataset.state === 'drawn' || f.dataset.state === 'error',
                               await auto.first().elementHandle(), { timeout: TIMEOUT_MS }).catch(() => {});
  else await page.waitForTimeout(300);
  const beforeChoice = glbScripts.length;
  if (beforeChoice > 1) fail(`${name}: ${beforeChoice} GLB scripts requested before any level was chosen`);
  const firstDraw = (await auto.count()) ? Number(await auto.first().getAttribute('data-drawn-ms')) || null : null;
  if (maxFirstDraw && !(firstDraw <= maxFirstDraw)) fail(`${name}: first draw after ${firstDraw} ms (at most ${maxFirstDraw})`);
  const { head, cards } = await readable(page);
  const views = [];
  for (let i = 0; i < count; i++) {
    const f = figures.nth(i);
    await f.scrollIntoViewIfNeeded();
    const src = await f.getAttribute('data-src');
    if ((await f.getAttribute('data-load')) === 'click' && (await f.getAttribute('data-state')) !== 'drawn')
      await f.locator('canvas').click();
    views.push(await waitDrawn(page, f, url, src));
    if (!levels) continue;
    const buttons = f.locator('button[data-src]');
    for (let b = 0; b < await buttons.count(); b++) {
      const button = buttons.nth(b);
      const bsrc = await button.getAttribute('data-src');
      if (bsrc === src) continue;
      await f.evaluate((e) => { e.dataset.state = 'switching'; });
      await button.click();
      views.push(await waitDrawn(page, f, url, bsrc));
    }
  }
  if (shots) {
    mkdirSync(shots, { recursive: true });
    await page.evaluate(() => window.scrollTo(0, 0));
    await page.screenshot({ path: join(shots, name.replace(/[^A-Za-z0-9._-]/g, '_') + '.png'), fullPage: true });
  }
  for (const e of errors) fail(`${name}: ${e}`);
  console.log(JSON.stringify({ page: name, url, views: count, errors: errors.length, first_draw_ms: firstDraw,
    glb_scripts_before_choice: beforeChoice, head, cards }));
  await page.close();
  return views;
}

const profile = mkdtempSync(join(tmpdir(), 'scanlod-chromium-'));
const server = httpRoot ? await serve(httpRoot) : null;
const origin = server ? `http://127.0.0.1:${server.address().port}` : null;
let context;
try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: findChromium(), headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--no-first-run', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', '--disable-quic'],
  });
  // Everything the pages ask for: allowed are their own files and in-page URLs.
  const allowed = (u) => u.startsWith('blob:') || u.startsWith('data:') ||
    (origin ? u.startsWith(origin + '/') : u.startsWith('file://'));
  context.on('request', (r) => { if (!allowed(r.url())) fail(`request leaves the page's files: ${r.url()}`); });
  await context.route('**/*', (route) => (allowed(route.request().url()) ? route.continue() : route.abort()));
  for (const p of pages) {
    let url;
    if (origin) {
      const rel = relative(httpRoot, p);
      if (rel.startsWith('..')) { fail(`${p} is not under ${httpRoot}`); continue; }
      url = origin + '/' + rel.split(sep).map(encodeURIComponent).join('/');
    } else url = pathToFileURL(p).href;
    const name = (origin ? 'http-' : 'file-') + relative(process.cwd(), p).split(sep).join('_');
    await checkPage(context, url, name);
  }
} catch (e) {
  fail('check_page: ' + (e && e.stack ? e.stack.split('\n').slice(0, 3).join(' ') : e));
} finally {
  if (context) await context.close();
  if (server) server.close();
  rmSync(profile, { recursive: true, force: true });
}
console.log(JSON.stringify({ pages: pages.length, failed }));
process.exit(failed ? 1 : 0);
