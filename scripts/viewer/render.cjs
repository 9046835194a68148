#!/usr/bin/env node
// node render.cjs MODEL.glb OUT.png [unlit] [side|front|top] [morph=W] [box=x0,y0,z0,x1,y1,z1]
// Serves render.html, three.js and MODEL.glb (as /model.glb) on 127.0.0.1, opens the page in
// headless Chromium (/usr/bin/chromium, or $CHROMIUM) through playwright-core, waits for
// the page's OK, and saves a 512 x 512 screenshot of the canvas. Prints one JSON line:
// what three.js loaded (textured, vertexColors, triangles, size, extensions). Exit 1 when
// the page fails, 2 on usage errors. Install once: npm ci --prefix scripts/viewer.
const http = require('http'), fs = require('fs'), os = require('os'), path = require('path');
const { chromium } = require('playwright-core');
const [model, out, ...opts] = process.argv.slice(2);
if (!model || !out) {
  console.error('usage: render.cjs MODEL.glb OUT.png [unlit] [side|front|top]');
  process.exit(2);
}
const here = __dirname;
const types = { '.html': 'text/html', '.js': 'text/javascript', '.wasm': 'application/wasm',
                '.glb': 'model/gltf-binary' };
const server = http.createServer((req, res) => {
  const url = decodeURIComponent(req.url.split('?')[0]);
  const file = url === '/model.glb' ? path.resolve(model)
             : path.join(here, path.normalize(url === '/' ? '/render.html' : url));
  if (url !== '/model.glb' && !file.startsWith(here + path.sep)) { res.writeHead(403); res.end(); return; }
  fs.readFile(file, (err, data) => {
    if (err) { res.writeHead(404); res.end(); return; }
    res.writeHead(200, { 'Content-Type': types[path.extname(file)] || 'application/octet-stream' });
    res.end(data);
  });
});
server.listen(0, '127.0.0.1', async () => {
  const port = server.address().port;
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'scanlod-chromium-'));
  let rc = 0;
  const ctx = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium', headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--no-first-run', '--disable-background-networking',
           '--disable-component-update', '--disable-sync'],
    viewport: { width: 512, height: 512 } });
  try {
    const page = ctx.pages()[0] || await ctx.newPage();
    page.on('pageerror', (e) => console.error('pageerror: ' + e));
    const query = new URLSearchParams({ view: opts.find((o) => /^(side|front|top)$/.test(o)) || 'side' });
    if (opts.includes('unlit')) query.set('unlit', '1');
    const morph = opts.find((o) => o.startsWith('morph='));
    if (morph) query.set('morph', morph.slice(6));
    const box = opts.find((o) => o.startsWith('box='));
    if (box) query.set('box', box.slice(4));
    await page.goto(`http://127.0.0.1:${port}/render.html?${query}`);
    await page.waitForFunction(() => document.title !== 'loading', null, { timeout: 120000 });
    const title = await page.title();
    if (title !== 'OK') throw new Error(title);
    await page.locator('#c').screenshot({ path: out });
    console.log(JSON.stringify(await page.evaluate(() => window.SCANLOD_INFO)));
  } catch (e) {
    console.error('render.cjs: ' + e.message);
    rc = 1;
  }
  await ctx.close();
  fs.rmSync(profile, { recursive: true, force: true });
  server.close();
  process.exit(rc);
});
