// gdsky oracle driver: serves the Godot Web export and the oracle's PCK on 127.0.0.1, runs them in
// headless Chromium through playwright-core, and relays jobs as JSON lines:
//   stdin  <- {"id": N, "op": "render" | "compile", ...}   one job per line, run in order
//   stdout -> {"event": "ready", ...} once, then {"id": N, "log": [...], "reply": {...}} per job,
//             or {"event": "fatal", "message": "..."} after which the driver exits.
// Diagnostics go to stderr. Closing stdin shuts the browser down. Written to a temporary directory and
// started by crates/skyoracle (src/process.rs): node driver.mjs ORACLE_DIR WORK_DIR CHROMIUM.
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import readline from 'node:readline';
import { createRequire } from 'node:module';

const [oracleDir, workDir, chromiumPath] = process.argv.slice(2);
const bootTimeoutMs = Number(process.env.SKYORACLE_BOOT_TIMEOUT_MS || 90000);
const defaultJobTimeoutMs = Number(process.env.SKYORACLE_JOB_TIMEOUT_MS || 300000);

// playwright-core lives in ORACLE_DIR/node_modules, not beside this temporary file.
const require = createRequire(path.join(oracleDir, 'package.json'));
const { chromium } = require('playwright-core');

const send = (obj) => process.stdout.write(JSON.stringify(obj) + '\n');
const note = (msg) => process.stderr.write(`driver: ${msg}\n`);

const PAGE = `<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>gdsky oracle</title></head>
<body style="margin:0;background:#000">
<canvas id="canvas" width="64" height="64"></canvas>
<script src="index.js"></script>
<script>
(() => {
  const log = [];
  const queue = [];
  // Called by main.gd through JavaScriptBridge.get_interface("oracle").
  globalThis.oracle = {
    ready: (info) => window.oracle_ready(info),
    take: () => {
      if (queue.length === 0) return '';
      const stray = log.splice(0);
      if (stray.length) window.oracle_stray(JSON.stringify(stray));
      return queue.shift();
    },
    put: (reply) => window.oracle_result(reply, JSON.stringify(log.splice(0))),
    push: (job) => { queue.push(job); },
  };
  // Godot does not recover a lost WebGL context (after a GPU process crash it draws nothing and reads
  // back black): make it fatal.
  document.getElementById('canvas').addEventListener('webglcontextlost', () => window.oracle_lost());
  const engine = new Engine({
    executable: 'index',
    mainPack: 'oracle.pck',
    canvas: document.getElementById('canvas'),
    canvasResizePolicy: 0,
    focusCanvas: false,
    args: ['--audio-driver', 'Dummy'],
    onPrint: (...a) => log.push(a.join(' ')),
    onPrintError: (...a) => log.push(a.join(' ')),
    onExit: (code) => window.oracle_exit(code),
  });
  engine.startGame().catch((e) => window.oracle_fatal(String((e && e.stack) || e)));
})();
</script>
</body></html>
`;

const TYPES = { '.js': 'text/javascript', '.wasm': 'application/wasm', '.png': 'image/png', '.pck': 'application/octet-stream' };

function serve(req, res) {
  const headers = {
    // Cross-origin isolation, as Godot's Web export asks of its server.
    'Cross-Origin-Opener-Policy': 'same-origin',
    'Cross-Origin-Embedder-Policy': 'require-corp',
    'Cross-Origin-Resource-Policy': 'same-origin',
    'Cache-Control': 'no-store',
  };
  const name = new URL(req.url, 'http://127.0.0.1').pathname;
  if (name === '/' || name === '/oracle.html') {
    res.writeHead(200, { ...headers, 'Content-Type': 'text/html; charset=utf-8' });
    res.end(PAGE);
    return;
  }
  if (name === '/favicon.ico') {
    res.writeHead(204, headers);
    res.end();
    return;
  }
  let file = null;
  if (name === '/oracle.pck') file = path.join(workDir, 'oracle.pck');
  else if (/^\/index(\.[a-z]+)+$/.test(name)) file = path.join(oracleDir, 'godot', name.slice(1));
  if (file === null || !fs.existsSync(file)) {
    res.writeHead(404, headers);
    res.end();
    return;
  }
  res.writeHead(200, { ...headers, 'Content-Type': TYPES[path.extname(file)] || 'application/octet-stream' });
  fs.createReadStream(file).pipe(res);
}

let browser = null;
let server = null;
let finished = false;

async function shutdown(code) {
  if (finished) return;
  finished = true;
  const hardStop = setTimeout(() => process.exit(code), 5000);
  try {
    if (browser) await browser.close();
  } catch (e) {
    note(`closing the browser: ${e}`);
  }
  if (server) server.close();
  // The work directory (this script and the pack) belongs to this run; the Rust side removes it too,
  // but not when its Oracle lives in a static that is never dropped.
  if (path.basename(workDir).startsWith('skyoracle-')) fs.rmSync(workDir, { recursive: true, force: true });
  clearTimeout(hardStop);
  process.exit(code);
}

function fatal(message, kind = 'crash') {
  if (finished) return;
  send({ event: 'fatal', kind, message });
  shutdown(1);
}

let pending = null; // { id, resolve, timer }

async function main() {
  server = http.createServer(serve);
  await new Promise((resolve, reject) => {
    server.once('error', reject);
    server.listen(0, '127.0.0.1', resolve);
  });
  const url = `http://127.0.0.1:${server.address().port}/oracle.html`;

  const started = Date.now();
  browser = await chromium.launch({
    executablePath: chromiumPath,
    headless: true,
    chromiumSandbox: false,
    timeout: 60000,
    // playwright-core gives each launch a fresh temporary profile; the first four flags keep Chromium off
    // the network. Without a GPU, headless Chromium paces WebGL frames at about 1 Hz (1 s per frame
    // whatever is drawn, measured); --disable-frame-rate-limit lets requestAnimationFrame run as fast as
    // frames render.
    args: [
      '--disable-background-networking',
      '--disable-component-update',
      '--disable-sync',
      '--no-first-run',
      '--disable-frame-rate-limit',
    ],
  });
  browser.on('disconnected', () => fatal('the browser disconnected'));
  const page = await browser.newPage({ viewport: { width: 64, height: 64 } });
  page.on('crash', () => fatal('the page crashed (Godot or the browser ran out of memory or hit a bug)'));
  // An uncaught exception stops Godot's main loop for good: report it rather than wait for a timeout.
  page.on('pageerror', (e) => fatal(`page error: ${(e && e.stack) || e}`));
  page.on('console', (m) => {
    // Godot reads every frame back; ANGLE's performance note about it would bury everything else.
    if (!m.text().includes('GPU stall due to ReadPixels')) note(`console.${m.type()}: ${m.text()}`);
  });

  let ready;
  const readyPromise = new Promise((resolve) => (ready = resolve));
  await page.exposeFunction('oracle_ready', (info) => ready(info));
  await page.exposeFunction('oracle_fatal', (message) => fatal(`Godot failed to start: ${message}`));
  await page.exposeFunction('oracle_exit', (code) => fatal(`Godot exited with code ${code}`));
  await page.exposeFunction('oracle_lost', () => fatal('the WebGL context was lost (the GPU process crashed or was reset)'));
  await page.exposeFunction('oracle_stray', (lines) => note(`log between jobs: ${lines}`));
  await page.exposeFunction('oracle_result', (reply, log) => {
    if (pending === null) {
      note('a reply arrived with no job pending');
      return;
    }
    const p = pending;
    pending = null;
    clearTimeout(p.timer);
    // The reply is Godot's JSON text; it is spliced in as is rather than parsed and re-serialized.
    process.stdout.write(`{"id":${JSON.stringify(p.id)},"log":${log},"reply":${reply}}\n`);
    p.resolve();
  });

  await page.goto(url, { timeout: bootTimeoutMs });
  const bootTimer = setTimeout(() => fatal(`Godot did not report ready within ${bootTimeoutMs} ms`, 'timeout'), bootTimeoutMs);
  const info = JSON.parse(await readyPromise);
  clearTimeout(bootTimer);
  const webgl = await page.evaluate(() => {
    const gl = document.createElement('canvas').getContext('webgl2');
    if (!gl) return { renderer: null, version: null };
    const ext = gl.getExtension('WEBGL_debug_renderer_info');
    return {
      renderer: ext ? gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER),
      version: gl.getParameter(gl.VERSION),
    };
  });
  send({ event: 'ready', boot_ms: Date.now() - started, godot: info, webgl, browser: browser.version() });

  const lines = readline.createInterface({ input: process.stdin, crlfDelay: Infinity });
  const jobs = [];
  let running = false;
  const pump = async () => {
    if (running) return;
    running = true;
    while (jobs.length > 0 && !finished) {
      const line = jobs.shift();
      let job;
      try {
        job = JSON.parse(line);
      } catch (e) {
        fatal(`a job line is not JSON: ${e}`);
        return;
      }
      const timeoutMs = Number(job.timeout_ms || defaultJobTimeoutMs);
      await new Promise((resolve) => {
        pending = {
          id: job.id,
          resolve,
          timer: setTimeout(() => fatal(`job ${job.id} (${job.op}) timed out after ${timeoutMs} ms`, 'timeout'), timeoutMs),
        };
        page.evaluate((text) => globalThis.oracle.push(text), line).catch((e) => fatal(`queueing job ${job.id}: ${e}`));
      });
    }
    running = false;
  };
  lines.on('line', (line) => {
    if (line.trim() === '') return;
    jobs.push(line);
    pump();
  });
  lines.on('close', () => shutdown(0));
}

process.on('unhandledRejection', (e) => fatal(`driver: ${(e && e.stack) || e}`));
main().catch((e) => fatal(`driver: ${(e && e.stack) || e}`));
