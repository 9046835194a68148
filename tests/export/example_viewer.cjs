#!/usr/bin/env node
// node example_viewer.cjs REPO MODEL.glb DISTANCE
// Opens examples/viewer/ (served from the repository REPO, MODEL.glb as /model.glb) in
// headless Chromium with the camera DISTANCE times the framing distance away, and prints
// the morph weight the viewer drew (window.SCANLOD_MORPH). Exit 1 when the page fails.
const http = require('http'), fs = require('fs'), os = require('os'), path = require('path');
const [repo, model, distance] = process.argv.slice(2);
const { chromium } = require(path.join(path.resolve(repo), 'scripts/viewer/node_modules/playwright-core'));
const types = { '.html': 'text/html', '.js': 'text/javascript', '.wasm': 'application/wasm',
                '.glb': 'model/gltf-binary' };
const root = path.resolve(repo);
const server = http.createServer((req, res) => {
  const url = decodeURIComponent(req.url.split('?')[0]);
  const file = url === '/model.glb' ? path.resolve(model)
             : path.join(root, path.normalize(url.endsWith('/') ? url + 'index.html' : url));
  if (url !== '/model.glb' && !file.startsWith(root + path.sep)) { res.writeHead(403); res.end(); return; }
  fs.readFile(file, (err, data) => {
    if (err) { res.writeHead(404); res.end(); return; }
    res.writeHead(200, { 'Content-Type': types[path.extname(file)] || 'application/octet-stream' });
    res.end(data);
  });
});
server.listen(0, '127.0.0.1', async () => {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'scanlod-chromium-'));
  let rc = 0;
  const ctx = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium', headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--no-first-run'], viewport: { width: 400, height: 400 } });
  try {
    const page = ctx.pages()[0] || await ctx.newPage();
    page.on('pageerror', (e) => console.error('pageerror: ' + e));
    await page.goto(`http://127.0.0.1:${server.address().port}/examples/viewer/?glb=/model.glb&distance=${distance}`);
    await page.waitForFunction(() => document.title !== 'loading', null, { timeout: 120000 });
    if (await page.title() !== 'OK') throw new Error(await page.title());
    console.log(JSON.stringify(await page.evaluate(() => window.SCANLOD_MORPH)));
  } catch (e) {
    console.error('example_viewer.cjs: ' + e.message);
    rc = 1;
  }
  await ctx.close();
  fs.rmSync(profile, { recursive: true, force: true });
  server.close();
  process.exit(rc);
});
