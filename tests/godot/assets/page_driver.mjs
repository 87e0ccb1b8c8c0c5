// Drives one page in headless Chromium with WebGPU (SwiftShader) for tests/godot/preview.rs:
//   node page_driver.mjs ORACLE_DIR CHROMIUM URL [no-webgpu]
// (`no-webgpu`: the page sees a browser without WebGPU, navigator.gpu undefined)
// then one JSON line per request on stdin, {"js": "expression"} or {"screenshot": "PATH.png"},
// answered on stdout by
// {"ok": true, "value": ...} or {"ok": false, "error": "..."}; the expression is evaluated in the
// page and awaited. The first line out is {"event": "loaded"} once the page has loaded.
// Console messages and page errors go to stderr. Closing stdin closes the browser.
import path from 'node:path';
import readline from 'node:readline';
import { createRequire } from 'node:module';

const [oracleDir, chromiumPath, url, mode] = process.argv.slice(2);
const require = createRequire(path.join(oracleDir, 'package.json'));
const { chromium } = require('playwright-core');

const browser = await chromium.launch({
  executablePath: chromiumPath,
  headless: true,
  chromiumSandbox: false,
  timeout: 60000,
  args: [
    '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run',
    '--headless=new', '--no-sandbox', '--enable-unsafe-webgpu', '--use-webgpu-adapter=swiftshader',
    '--enable-unsafe-swiftshader', '--disable-frame-rate-limit',
  ],
});
const page = await browser.newPage({ viewport: { width: 1200, height: 700 } });
page.on('console', (m) => console.error(`console.${m.type()}: ${m.text()}`));
page.on('pageerror', (e) => console.error(`pageerror: ${(e && e.stack) || e}`));
if (mode === 'no-webgpu') await page.addInitScript(() => Object.defineProperty(navigator, 'gpu', { value: undefined }));
await page.goto(url);
console.log(JSON.stringify({ event: 'loaded' }));

const lines = readline.createInterface({ input: process.stdin });
for await (const line of lines) {
  if (!line.trim()) continue;
  try {
    const { js, screenshot } = JSON.parse(line);
    const value = screenshot ? (await page.screenshot({ path: screenshot }), screenshot) : await page.evaluate(js);
    console.log(JSON.stringify({ ok: true, value: value === undefined ? null : value }));
  } catch (e) {
    console.log(JSON.stringify({ ok: false, error: String((e && e.message) || e) }));
  }
}
await browser.close();
