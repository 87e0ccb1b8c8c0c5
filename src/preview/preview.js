// gdsky preview: the converted module in WebGPU, the inspector from the reflection, reload on save.
// window.gdsky is the page's state and its test hooks (tests/godot/preview.rs drives them).
'use strict';
const $ = (id) => document.getElementById(id);
const G = (window.gdsky = {
  ready: false, frames: 0, version: -1, error: null, compileMessages: [], pixels: null, width: 0, height: 0,
  frameMs: 0, reloads: 0,
});
const RAD = Math.PI / 180; // as Rust's f64::to_radians: x · (π / 180)
let device, st, scene, layouts, pipelines = {}, groups = [], buffers = {}, material, exposure = 0.5;
let playing = false, speed = 1, dirty = true, busy = false, lastT = performance.now();
const edited = new Map(); // uniform name → values the user set on the page
const dropped = new Map(); // "group:binding" → a texture the user dropped on the page
let served = []; // the textures the server sent

const status = (text) => ($('status').textContent = text);
function showError(text) {
  const box = $('error');
  box.style.display = text ? 'block' : 'none';
  box.textContent = text || '';
}

async function init() {
  if (!navigator.gpu) return noWebGPU('this browser has no WebGPU (navigator.gpu is missing)');
  const adapter = await navigator.gpu.requestAdapter();
  if (!adapter) return noWebGPU('WebGPU is present but gave no adapter');
  device = await adapter.requestDevice();
  device.lost.then((info) => { G.error = `the WebGPU device was lost: ${info.message}`; showError(G.error); });
  await loadState(true);
  const events = new EventSource('/events');
  events.addEventListener('state', (e) => { if (Number(e.data) !== G.version) loadState(false); });
  wireBar();
  requestAnimationFrame(loop);
}

// Without WebGPU: say so, and show gdsky's own render (Vulkan, on the server) of the start state.
async function noWebGPU(why) {
  const box = $('nogpu');
  box.style.display = 'block';
  box.textContent = `gdsky preview needs WebGPU for a live sky: ${why}. Use Chrome or Edge (113+), or ` +
    'Firefox/Safari with WebGPU enabled. Below: gdsky\'s own render of this sky (Vulkan, on the server).';
  status('no WebGPU: showing gdsky\'s render');
  G.error = why;
  const s = await (await fetch('/state.json', { cache: 'no-store' })).json();
  if (!s.wgsl) return showError(s.error);
  st = s;
  scene = structuredClone(s.scene);
  material = new Uint8Array(await (await fetch('/material.bin', { cache: 'no-store' })).arrayBuffer());
  const image = await lavapipe();
  G.pixels = image.pixels;
  G.width = image.width;
  G.height = image.height;
  show(image.pixels, image.width, image.height);
  G.fallbackFrames = (G.fallbackFrames || 0) + 1;
}

// gdsky's render of the page's state (the server's Vulkan device): {width, height, pixels}.
async function lavapipe() {
  const body = JSON.stringify({
    projection: scene.projection, width: scene.width, height: scene.height, time: scene.time,
    lights: scene.lights, camera: scene.camera, material: Array.from(material),
  });
  const response = await fetch('/render', { method: 'POST', body, headers: { 'Content-Type': 'application/json' } });
  if (!response.ok) throw new Error(`gdsky render: ${await response.text()}`);
  const width = Number(response.headers.get('X-Width')), height = Number(response.headers.get('X-Height'));
  return { width, height, pixels: new Float32Array(await response.arrayBuffer()) };
}

// The page's frame beside gdsky's render of the same state, and their relative error per pixel
// (the largest of R, G, B; |a − b| / max(|b|, 1e-4), as `gdsky compare`).
async function compare() {
  await G.nextFrame();
  const page = { pixels: G.pixels, width: G.width, height: G.height };
  const theirs = await lavapipe();
  if (theirs.width !== page.width || theirs.height !== page.height) throw new Error('the two images differ in size');
  const n = page.width * page.height, rel = new Float64Array(n);
  for (let i = 0; i < n; i++) {
    let worst = 0;
    for (let c = 0; c < 3; c++) {
      const a = page.pixels[4 * i + c], b = theirs.pixels[4 * i + c];
      worst = Math.max(worst, Math.abs(a - b) / Math.max(Math.abs(b), 1e-4));
    }
    rel[i] = worst;
  }
  const sorted = Float64Array.from(rel).sort();
  const stats = { max: sorted[n - 1], p99: sorted[Math.max(0, Math.ceil(0.99 * n) - 1)], mean: sorted.reduce((a, b) => a + b, 0) / n };
  show(page.pixels, page.width, page.height, $('compare-page'));
  show(theirs.pixels, theirs.width, theirs.height, $('compare-gdsky'));
  const heat = $('compare-heat');
  heat.width = page.width;
  heat.height = page.height;
  const ctx = heat.getContext('2d'), image = ctx.createImageData(page.width, page.height);
  for (let i = 0; i < n; i++) {
    const t = rel[i] > 0 ? Math.min(1, Math.max(0, (Math.log10(rel[i]) + 6) / 5)) : 0;
    image.data.set([255 * Math.min(1, 2 * t), 255 * Math.max(0, 2 * t - 1), 255 * Math.max(0, 1 - 2 * Math.abs(t - 0.35)), 255], 4 * i);
  }
  ctx.putImageData(image, 0, 0);
  $('compare').style.display = 'block';
  $('compare-stats').textContent = `relative error of this page against gdsky render: max ${stats.max.toExponential(2)}, ` +
    `p99 ${stats.p99.toExponential(2)}, mean ${stats.mean.toExponential(2)} (${page.width}×${page.height})`;
  G.comparison = stats;
  return stats;
}

async function loadState(first) {
  const s = await (await fetch('/state.json', { cache: 'no-store' })).json();
  G.version = s.version;
  G.error = s.error;
  showError(s.error ? `${s.error}\n(the frame is the last good one)` : '');
  if (!s.wgsl) { status(s.error ? 'the shader has errors' : 'no shader'); return; }
  const bytes = new Uint8Array(await (await fetch('/material.bin', { cache: 'no-store' })).arrayBuffer());
  const textures = await Promise.all(s.textures.map(async (t) =>
    ({ ...t, data: new Uint8Array(await (await fetch(t.url, { cache: 'no-store' })).arrayBuffer()) })));
  try {
    await build(s, textures);
  } catch (e) {
    G.error = String(e.message || e);
    showError(G.error);
    return;
  }
  const previous = st;
  st = s;
  material = bytes;
  if (first || !scene) scene = structuredClone(s.scene);
  // The page's own edits survive a reload when the uniform is still there with its type.
  for (const [name, values] of edited) {
    const u = uniforms().find((x) => x.name === name);
    if (u && values.length === components(u.type)) writeUniform(u, values); else edited.delete(name);
  }
  buildInspector();
  if (first) buildSceneControls();
  G.reloads += previous ? 1 : 0;
  G.ready = true;
  dirty = true;
}

// --- the module ----------------------------------------------------------------------------------

async function build(s, textures) {
  device.pushErrorScope('validation');
  const module = device.createShaderModule({ code: s.wgsl, label: s.name });
  const info = await module.getCompilationInfo();
  G.compileMessages = info.messages.map((m) => ({ type: m.type, line: m.lineNum, col: m.linePos, message: m.message }));
  const errors = info.messages.filter((m) => m.type === 'error');
  if (errors.length) {
    await device.popErrorScope();
    throw new Error('Chromium\'s WebGPU (Tint) refused the WGSL gdsky emitted (a gdsky bug; please report it):\n' +
      errors.map((m) => `line ${m.lineNum}:${m.linePos}: ${m.message}`).join('\n'));
  }
  G.textureCount = textures.length;
  const maxGroup = Math.max(0, ...s.bindings.map((b) => b.group));
  layouts = [];
  for (let g = 0; g <= maxGroup; g++) {
    const entries = s.bindings.filter((b) => b.group === g).map((b) => {
      const e = { binding: b.binding, visibility: GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT };
      if (b.kind === 'uniform') e.buffer = { type: 'uniform' };
      else if (b.kind === 'sampler') e.sampler = { type: 'filtering' };
      else e.texture = { sampleType: b.sample_type, viewDimension: b.dimension };
      return e;
    });
    layouts.push(device.createBindGroupLayout({ entries }));
  }
  const layout = device.createPipelineLayout({ bindGroupLayouts: layouts });
  const fragments = s.reflection.entry_points.fragment;
  pipelines = {};
  for (const [projection, entry] of Object.entries(fragments)) {
    pipelines[projection] = await device.createRenderPipelineAsync({
      layout,
      vertex: { module, entryPoint: s.reflection.entry_points.vertex },
      fragment: { module, entryPoint: entry, targets: [{ format: 'rgba32float' }] },
      primitive: { topology: 'triangle-list' },
    });
  }
  // Textures the user dropped on the page stay while their binding does.
  for (const [key, t] of dropped) {
    if (!s.bindings.some((b) => `${b.group}:${b.binding}` === key && b.kind === 'texture')) dropped.delete(key);
  }
  served = textures;
  makeGroups(s);
  const error = await device.popErrorScope();
  if (error) throw new Error(`WebGPU refused the pipeline: ${error.message}`);
}

// The bind groups: fresh uniform buffers (each frame writes them), the served textures with
// the dropped ones over them, stand-ins for the rest.
function makeGroups(s) {
  buffers = {};
  groups = layouts.map((layout, g) => {
    const entries = s.bindings.filter((b) => b.group === g).map((b) => ({ binding: b.binding, resource: resource(s, b) }));
    return device.createBindGroup({ layout, entries });
  });
}

function resource(s, b) {
  const textures = [...dropped.values(), ...served];
  if (b.kind === 'uniform') {
    const buffer = device.createBuffer({ size: Math.max(16, b.size), usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    buffers[`${b.group}:${b.binding}`] = buffer;
    return { buffer };
  }
  if (b.kind === 'sampler') {
    const sampler = s.reflection.bindings.samplers.find((x) => x.group === b.group && x.binding === b.binding);
    const filter = sampler ? sampler.filter : 'linear';
    const nearest = filter.startsWith('nearest');
    const address = sampler && sampler.repeat ? 'repeat' : 'clamp-to-edge';
    return device.createSampler({
      addressModeU: address, addressModeV: address, addressModeW: address,
      magFilter: nearest ? 'nearest' : 'linear', minFilter: nearest ? 'nearest' : 'linear',
      mipmapFilter: filter.includes('mipmap') ? 'linear' : 'nearest',
    });
  }
  const given = textures.find((t) => t.group === b.group && t.binding === b.binding);
  return given ? upload(given) : standIn(s, b);
}

function upload(t) {
  const bpt = t.bytes_per_texel;
  const texture = device.createTexture({
    size: [t.width, t.height, t.layers], format: t.format, mipLevelCount: t.levels.length,
    dimension: t.dimension === '3d' ? '3d' : '2d', usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST,
  });
  let offset = 0;
  t.levels.forEach(([w, h], level) => {
    const layers = t.dimension === '3d' ? Math.max(1, t.layers >> level) : t.layers;
    const size = w * h * layers * bpt;
    device.queue.writeTexture({ texture, mipLevel: level }, t.data.subarray(offset, offset + size),
      { bytesPerRow: w * bpt, rowsPerImage: h }, [w, h, layers]);
    offset += size;
  });
  return texture.createView({ dimension: t.dimension });
}

// A 1×1 texture holding the hint's default texel, as gdsky's renderer binds one.
function standIn(s, b) {
  const entry = s.reflection.bindings.textures.find((t) => t.group === b.group && t.binding === b.binding);
  let texel = [1, 1, 1, 1];
  if (entry && entry.default === 'black') texel = [0, 0, 0, 1];
  else if (entry && entry.default === 'transparent') texel = [0, 0, 0, 0];
  else if (entry && entry.hints.includes('hint_normal')) texel = [0.5, 0.5, 1, 1];
  const layers = b.dimension === 'cube' ? 6 : 1;
  let format = 'rgba16float', data;
  if (b.sample_type === 'sint' || b.sample_type === 'uint') {
    format = b.sample_type === 'sint' ? 'rgba32sint' : 'rgba32uint';
    data = new Uint8Array(new Int32Array(texel).buffer);
  } else {
    const half = { 0: 0, 0.5: 0x3800, 1: 0x3c00 };
    data = new Uint8Array(new Uint16Array(texel.map((v) => half[v])).buffer);
  }
  const texture = device.createTexture({
    size: [1, 1, layers], format, dimension: b.dimension === '3d' ? '3d' : '2d',
    usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST,
  });
  for (let layer = 0; layer < layers; layer++) {
    device.queue.writeTexture({ texture, origin: [0, 0, layer] }, data, { bytesPerRow: data.length }, [1, 1, 1]);
  }
  return texture.createView({ dimension: b.dimension });
}

// --- the built-ins, as skydraw's SkyBuiltins::from_scene -------------------------------------------

function direction(elevationDeg, azimuthDeg) {
  const e = elevationDeg * RAD, a = azimuthDeg * RAD;
  return [Math.cos(e) * Math.sin(a), Math.sin(e), -Math.cos(e) * Math.cos(a)];
}

// Columns right, up, back of R_y(yaw) · R_x(pitch).
function basis(yawDeg, pitchDeg) {
  const a = yawDeg * RAD, b = pitchDeg * RAD;
  const [sa, ca, sb, cb] = [Math.sin(a), Math.cos(a), Math.sin(b), Math.cos(b)];
  return [[ca, 0, -sa], [sa * sb, cb, ca * sb], [sa * cb, -sb, ca * cb]];
}

function builtins(width, height, face) {
  const b = st.reflection.bindings.builtins, o = b.offsets, lo = b.light_offsets;
  const bytes = new ArrayBuffer(b.size), F = new Float32Array(bytes), U = new Uint32Array(bytes);
  const cam = scene.camera, m = basis(cam.yaw_deg, cam.pitch_deg);
  for (let c = 0; c < 3; c++) F.set(m[c], o.camera_basis / 4 + 4 * c);
  F.set(cam.position, o.position / 4);
  F[o.time / 4] = scene.time;
  F.set([width, height], o.screen_size / 4);
  F[o.tan_half_fov / 4] = Math.tan(cam.fov_deg * RAD * 0.5);
  U[o.render_pass / 4] = face === undefined ? 0 : 3;
  F[o.luminance_multiplier / 4] = 1;
  U[o.cube_face / 4] = face === undefined ? 0 : face;
  scene.lights.forEach((l, i) => {
    const at = (o.lights + i * b.light_stride) / 4;
    F.set(direction(l.elevation_deg, l.azimuth_deg), at + lo.direction / 4);
    F[at + lo.energy / 4] = l.energy;
    F.set(l.color, at + lo.color / 4);
    F[at + lo.size / 4] = l.size_deg * RAD;
    U[at + lo.enabled / 4] = l.enabled ? 1 : 0;
  });
  return bytes;
}

// --- rendering and read-back ---------------------------------------------------------------------

async function render() {
  const cube = scene.projection === 'cubemap';
  const side = scene.width, width = cube ? side * 6 : scene.width, height = cube ? side : scene.height;
  const bytesPerRow = Math.ceil((width * 16) / 256) * 256;
  const readback = device.createBuffer({ size: bytesPerRow * height, usage: GPUBufferUsage.COPY_DST | GPUBufferUsage.MAP_READ });
  const views = cube ? [0, 1, 2, 3, 4, 5] : [undefined];
  const materialBuffer = buffers['1:0'];
  if (materialBuffer && material.length) device.queue.writeBuffer(materialBuffer, 0, material);
  const pipeline = pipelines[scene.projection];
  const started = performance.now();
  for (const face of views) {
    const w = cube ? side : width;
    device.queue.writeBuffer(buffers['0:0'], 0, builtins(w, height, face));
    const target = device.createTexture({ size: [w, height], format: 'rgba32float', usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC });
    const encoder = device.createCommandEncoder();
    const pass = encoder.beginRenderPass({ colorAttachments: [{ view: target.createView(), loadOp: 'clear', storeOp: 'store', clearValue: [0, 0, 0, 0] }] });
    pass.setPipeline(pipeline);
    groups.forEach((g, i) => pass.setBindGroup(i, g));
    pass.draw(3);
    pass.end();
    encoder.copyTextureToBuffer({ texture: target }, { buffer: readback, offset: (face || 0) * side * 16, bytesPerRow, rowsPerImage: height }, [w, height]);
    device.queue.submit([encoder.finish()]);
    target.destroy();
  }
  await readback.mapAsync(GPUMapMode.READ);
  const mapped = new Float32Array(readback.getMappedRange());
  const pixels = new Float32Array(width * height * 4);
  for (let y = 0; y < height; y++) pixels.set(mapped.subarray((y * bytesPerRow) / 4, (y * bytesPerRow) / 4 + width * 4), y * width * 4);
  readback.unmap();
  readback.destroy();
  G.frameMs = performance.now() - started;
  G.pixels = pixels;
  G.width = width;
  G.height = height;
  show(pixels, width, height);
  G.frames++;
  status(`${st.name} · v${G.version} · ${width}×${height} · ${G.frameMs.toFixed(1)} ms`);
}

// The tone map of `gdsky render --png`: 1 − exp(−L · exposure), then a 1/2.2 power.
function show(pixels, width, height, canvas = $('sky')) {
  canvas.width = width;
  canvas.height = height;
  const ctx = canvas.getContext('2d');
  const image = ctx.createImageData(width, height);
  for (let i = 0; i < width * height; i++) {
    const [r, g, b] = [pixels[4 * i], pixels[4 * i + 1], pixels[4 * i + 2]];
    let rgb;
    if ([r, g, b].some(Number.isNaN)) rgb = [255, 0, 255];
    else if ([r, g, b].some((c) => !Number.isFinite(c))) rgb = [0, 255, 255];
    else rgb = [r, g, b].map((c) => Math.round(Math.min(1, Math.max(0, (1 - Math.exp(-Math.max(c, 0) * exposure)) ** (1 / 2.2))) * 255));
    image.data.set([...rgb, 255], 4 * i);
  }
  ctx.putImageData(image, 0, 0);
}

function loop(now) {
  if (playing) {
    scene.time += ((now - lastT) / 1000) * speed;
    $('time').value = scene.time.toFixed(2);
    dirty = true;
  }
  lastT = now;
  if (dirty && !busy && st && pipelines[scene.projection]) {
    dirty = false;
    busy = true;
    render().catch((e) => { G.error = String(e.message || e); showError(G.error); }).finally(() => { busy = false; });
  }
  requestAnimationFrame(loop);
}

// --- the inspector -------------------------------------------------------------------------------

const uniforms = () => st.reflection.uniforms.filter((u) => u.block === 'material' && u.array_stride === null);
const components = (type) => ({ vec2: 2, vec3: 3, vec4: 4, ivec2: 2, ivec3: 3, ivec4: 4, uvec2: 2, uvec3: 3, uvec4: 4, bvec2: 2, bvec3: 3, bvec4: 4 }[type] || 1);
const scalar = (type) => (type.startsWith('i') ? 'int' : type.startsWith('u') ? 'uint' : type.startsWith('b') ? 'bool' : 'float');

function readUniform(u) {
  const view = new DataView(material.buffer, material.byteOffset);
  const kind = scalar(u.type);
  return Array.from({ length: components(u.type) }, (_, i) => {
    const at = u.offset + 4 * i;
    return kind === 'float' ? view.getFloat32(at, true) : kind === 'int' ? view.getInt32(at, true) : view.getUint32(at, true);
  });
}

function writeUniform(u, values) {
  const view = new DataView(material.buffer, material.byteOffset);
  const kind = scalar(u.type);
  values.forEach((v, i) => {
    const at = u.offset + 4 * i;
    if (kind === 'float') view.setFloat32(at, v, true);
    else if (kind === 'int') view.setInt32(at, Math.round(v), true);
    else view.setUint32(at, kind === 'bool' ? (v ? 1 : 0) : Math.max(0, Math.round(v)), true);
  });
  dirty = true;
}

function setUniform(name, values) {
  const u = uniforms().find((x) => x.name === name);
  if (!u) throw new Error(`no material uniform \`${name}\``);
  values = Array.isArray(values) ? values : [values];
  writeUniform(u, values);
  edited.set(name, values);
  buildInspector();
}

function section(parent, title, open) {
  const details = document.createElement('details');
  details.open = open;
  const summary = document.createElement('summary');
  summary.textContent = title;
  details.append(summary);
  parent.append(details);
  return details;
}

function buildInspector() {
  const root = $('uniforms');
  root.textContent = '';
  const sections = new Map();
  const place = (group) => {
    const path = group ? group.split('.') : ['Uniforms'];
    let parent = root, key = '';
    for (const part of path) {
      key += `/${part}`;
      if (!sections.has(key)) sections.set(key, section(parent, part, true));
      parent = sections.get(key);
    }
    return parent;
  };
  for (const u of uniforms()) place(u.group).append(control(u));
  const slots = st.reflection.bindings.textures;
  if (slots.length) {
    const box = section(root, 'Textures', true);
    for (const slot of slots) box.append(textureRow(slot));
  }
}

// One texture: what is bound (a served texture, one dropped here, or the hint's stand-in), a
// thumbnail of a 2D 8-bit one, and a drop target: a PNG, JPEG or WebP dropped on the row replaces
// it (one level, 8-bit; `source_color` decodes it as sRGB, as gdsky does).
function textureRow(slot) {
  const key = `${slot.group}:${slot.binding}`;
  const t = dropped.get(key) || served.find((x) => `${x.group}:${x.binding}` === key);
  const div = row(slot.name, slot.doc || `${slot.type} ${slot.name}`);
  div.dataset.texture = slot.name;
  const info = document.createElement('span');
  info.textContent = t ? `${t.width}×${t.height}${t.layers > 1 ? `×${t.layers}` : ''} ${t.format}${dropped.has(key) ? ' (dropped)' : ''}`
    : `stand-in (${slot.default || (slot.hints.includes('hint_normal') ? 'normal' : 'white')}); drop an image here`;
  const thumb = document.createElement('canvas');
  thumb.style.width = '48px';
  if (t && t.dimension === '2d' && t.bytes_per_texel === 4) {
    thumb.width = t.width;
    thumb.height = t.height;
    const image = thumb.getContext('2d').createImageData(t.width, t.height);
    image.data.set(t.data.subarray(0, t.width * t.height * 4));
    thumb.getContext('2d').putImageData(image, 0, 0);
  } else {
    thumb.width = thumb.height = 1;
  }
  div.append(info, thumb);
  div.addEventListener('dragover', (e) => e.preventDefault());
  div.addEventListener('drop', (e) => {
    e.preventDefault();
    const file = e.dataTransfer.files[0];
    if (file) replaceTexture(slot, file).catch((err) => showError(`${file.name}: ${err.message || err}`));
  });
  return div;
}

async function replaceTexture(slot, blob) {
  const binding = st.bindings.find((b) => b.group === slot.group && b.binding === slot.binding);
  if (!binding || binding.dimension !== '2d') throw new Error('only a 2D texture can be replaced by dropping an image');
  const bitmap = await createImageBitmap(blob, { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
  const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
  const ctx = canvas.getContext('2d');
  ctx.drawImage(bitmap, 0, 0);
  const data = new Uint8Array(ctx.getImageData(0, 0, bitmap.width, bitmap.height).data.buffer);
  dropped.set(`${slot.group}:${slot.binding}`, {
    name: slot.name, group: slot.group, binding: slot.binding, width: bitmap.width, height: bitmap.height, layers: 1,
    levels: [[bitmap.width, bitmap.height]], format: slot.srgb ? 'rgba8unorm-srgb' : 'rgba8unorm', bytes_per_texel: 4,
    dimension: '2d', data,
  });
  makeGroups(st);
  buildInspector();
  dirty = true;
}

function row(labelText, title) {
  const div = document.createElement('div');
  div.className = 'row';
  const label = document.createElement('label');
  label.textContent = labelText;
  if (title) { label.title = title; div.title = title; }
  div.append(label);
  return div;
}

function numberInput(value, step, onInput) {
  const input = document.createElement('input');
  input.type = 'number';
  input.step = step;
  input.value = String(Number(value.toPrecision(6)));
  input.addEventListener('input', () => Number.isFinite(input.valueAsNumber) && onInput(input.valueAsNumber));
  return input;
}

function control(u) {
  const div = row(u.name, u.doc || `${u.type} ${u.name}`);
  div.dataset.uniform = u.name;
  const values = readUniform(u);
  const set = (vs) => { writeUniform(u, vs); edited.set(u.name, vs); };
  const range = u.hints.find((h) => h.name === 'hint_range');
  const color = u.hints.some((h) => h.name === 'source_color') && (u.type === 'vec3' || u.type === 'vec4');
  const kind = scalar(u.type);
  if (color) {
    const pick = document.createElement('input');
    pick.type = 'color';
    const hex = (v) => Math.round(Math.min(1, Math.max(0, v)) * 255).toString(16).padStart(2, '0');
    pick.value = `#${values.slice(0, 3).map(hex).join('')}`;
    pick.addEventListener('input', () => {
      const rgb = [1, 3, 5].map((i) => parseInt(pick.value.slice(i, i + 2), 16) / 255);
      set(u.type === 'vec4' ? [...rgb, readUniform(u)[3]] : rgb);
    });
    div.append(pick, document.createElement('span'));
  } else if (kind === 'bool' && values.length === 1) {
    const box = document.createElement('input');
    box.type = 'checkbox';
    box.checked = values[0] !== 0;
    box.addEventListener('change', () => set([box.checked ? 1 : 0]));
    div.append(box, document.createElement('span'));
  } else if (range && values.length === 1) {
    const [min, max, step] = range.args.map(Number);
    const slider = document.createElement('input');
    slider.type = 'range';
    slider.min = min; slider.max = max; slider.step = step || (kind === 'float' ? 'any' : 1);
    slider.value = values[0];
    const number = numberInput(values[0], slider.step, (v) => { slider.value = v; set([v]); });
    slider.addEventListener('input', () => { number.value = slider.value; set([slider.valueAsNumber]); });
    div.append(slider, number);
  } else {
    const box = document.createElement('div');
    box.className = 'vec';
    const current = values.slice();
    values.forEach((v, i) => box.append(numberInput(v, kind === 'float' ? 'any' : 1, (x) => { current[i] = x; set(current.slice()); })));
    div.append(box, document.createElement('span'));
  }
  return div;
}

// The sun, the camera and the bar.
function slider(parent, name, min, max, step, get, put) {
  const div = row(name);
  const s = document.createElement('input');
  s.type = 'range'; s.min = min; s.max = max; s.step = step; s.value = get();
  s.dataset.control = name;
  const n = numberInput(get(), step, (v) => { s.value = v; put(v); dirty = true; });
  s.addEventListener('input', () => { n.value = s.value; put(s.valueAsNumber); dirty = true; });
  div.append(s, n);
  parent.append(div);
}

function buildSceneControls() {
  const sun = () => scene.lights[0], cam = () => scene.camera;
  $('sun').textContent = '';
  slider($('sun'), 'elevation °', -90, 90, 0.1, () => sun().elevation_deg, (v) => (sun().elevation_deg = v));
  slider($('sun'), 'azimuth °', -180, 180, 0.1, () => sun().azimuth_deg, (v) => (sun().azimuth_deg = v));
  slider($('sun'), 'energy', 0, 16, 0.01, () => sun().energy, (v) => (sun().energy = v));
  slider($('sun'), 'size °', 0, 10, 0.01, () => sun().size_deg, (v) => (sun().size_deg = v));
  const colour = row('colour');
  const pick = document.createElement('input');
  pick.type = 'color';
  const hex = (v) => Math.round(Math.min(1, Math.max(0, v)) * 255).toString(16).padStart(2, '0');
  pick.value = `#${sun().color.map(hex).join('')}`;
  pick.addEventListener('input', () => { sun().color = [1, 3, 5].map((i) => parseInt(pick.value.slice(i, i + 2), 16) / 255); dirty = true; });
  colour.append(pick, document.createElement('span'));
  $('sun').append(colour);
  for (let i = 1; i < scene.lights.length; i++) {
    const box = $(`light${i}`);
    if (!box) continue;
    const light = () => scene.lights[i];
    box.textContent = '';
    const on = row('enabled');
    const check = document.createElement('input');
    check.type = 'checkbox';
    check.checked = light().enabled;
    check.addEventListener('change', () => { light().enabled = check.checked; dirty = true; });
    on.append(check, document.createElement('span'));
    box.append(on);
    slider(box, 'elevation °', -90, 90, 0.1, () => light().elevation_deg, (v) => (light().elevation_deg = v));
    slider(box, 'azimuth °', -180, 180, 0.1, () => light().azimuth_deg, (v) => (light().azimuth_deg = v));
    slider(box, 'energy', 0, 16, 0.01, () => light().energy, (v) => (light().energy = v));
    slider(box, 'size °', 0, 10, 0.01, () => light().size_deg, (v) => (light().size_deg = v));
  }
  $('camera').textContent = '';
  slider($('camera'), 'yaw °', -180, 180, 0.1, () => cam().yaw_deg, (v) => (cam().yaw_deg = v));
  slider($('camera'), 'pitch °', -89, 89, 0.1, () => cam().pitch_deg, (v) => (cam().pitch_deg = v));
  slider($('camera'), 'fov °', 1, 179, 0.1, () => cam().fov_deg, (v) => (cam().fov_deg = v));
  slider($('camera'), 'height m', 0, 100000, 1, () => cam().position[1], (v) => (cam().position[1] = v));
  $('projection').value = scene.projection;
  $('time').value = scene.time;
}

function wireBar() {
  $('projection').addEventListener('change', () => { scene.projection = $('projection').value; dirty = true; });
  $('play').addEventListener('click', () => { playing = !playing; $('play').textContent = playing ? '⏸' : '▶'; });
  $('time').addEventListener('input', () => { scene.time = $('time').valueAsNumber || 0; dirty = true; });
  $('speed').addEventListener('change', () => (speed = Number($('speed').value)));
  $('exposure').addEventListener('input', () => { exposure = $('exposure').valueAsNumber; if (G.pixels) show(G.pixels, G.width, G.height); });
  // Drag on the sky: the panorama places the sun where the pointer is; the camera looks around.
  let drag = null;
  const canvas = $('sky');
  canvas.addEventListener('pointerdown', (e) => { drag = { x: e.clientX, y: e.clientY }; canvas.setPointerCapture(e.pointerId); pointer(e); });
  canvas.addEventListener('pointermove', (e) => drag && pointer(e));
  canvas.addEventListener('pointerup', () => (drag = null));
  function pointer(e) {
    const r = canvas.getBoundingClientRect();
    const u = (e.clientX - r.left) / r.width, v = (e.clientY - r.top) / r.height;
    if (scene.projection === 'panorama' || e.shiftKey) {
      if (scene.projection !== 'panorama') return;
      scene.lights[0].elevation_deg = 90 - 180 * v;
      scene.lights[0].azimuth_deg = ((360 * u + 180) % 360) - 180;
    } else if (scene.projection === 'camera') {
      scene.camera.yaw_deg -= (e.clientX - drag.x) * 0.3;
      scene.camera.pitch_deg = Math.max(-89, Math.min(89, scene.camera.pitch_deg - (e.clientY - drag.y) * 0.3));
      drag = { x: e.clientX, y: e.clientY };
    }
    buildSceneControls();
    dirty = true;
  }
  $('compare-button').addEventListener('click', () => compare().catch((e) => showError(String(e.message || e))));
  $('export-set').addEventListener('click', () => ($('export').value = exportFlags()));
  $('export-toml').addEventListener('click', () => ($('export').value = exportToml()));
  $('export-tres').addEventListener('click', () => ($('export').value = exportTres()));
}

// --- export ----------------------------------------------------------------------------------------

const num = (v) => String(Number(Number(v).toPrecision(7)));
const valueText = (u) => readUniform(u).map((v) => (scalar(u.type) === 'bool' ? (v ? 'true' : 'false') : num(v))).join(',');

function exportFlags() {
  const sun = scene.lights[0], cam = scene.camera;
  const flags = [`--projection ${scene.projection}`, `--size ${scene.width}x${scene.height}`, `--time ${num(scene.time)}`,
    `--sun ${num(sun.elevation_deg)},${num(sun.azimuth_deg)}`, `--sun-energy ${num(sun.energy)}`,
    `--sun-color ${sun.color.map(num).join(',')}`, `--sun-size ${num(sun.size_deg)}`,
    `--position ${cam.position.map(num).join(',')}`, `--yaw ${num(cam.yaw_deg)}`, `--pitch ${num(cam.pitch_deg)}`, `--fov ${num(cam.fov_deg)}`];
  for (const u of uniforms()) flags.push(`--set ${u.name}=${valueText(u)}`);
  return flags.join(' \\\n  ');
}

function exportToml() {
  const sun = scene.lights[0], cam = scene.camera;
  const list = (vs) => `[${vs.map(num).join(', ')}]`;
  const lines = [`projection = "${scene.projection}"`, `size = [${scene.width}, ${scene.height}]`, `time = ${num(scene.time)}`, '',
    '[sun]', `elevation = ${num(sun.elevation_deg)}`, `azimuth = ${num(sun.azimuth_deg)}`, `enabled = ${sun.enabled}`,
    `energy = ${num(sun.energy)}`, `color = ${list(sun.color)}`, `size = ${num(sun.size_deg)}`, '',
    '[camera]', `position = ${list(cam.position)}`, `fov = ${num(cam.fov_deg)}`, `yaw = ${num(cam.yaw_deg)}`, `pitch = ${num(cam.pitch_deg)}`, '',
    '[uniforms]'];
  for (const u of uniforms()) {
    const vs = readUniform(u), bool = scalar(u.type) === 'bool';
    const text = vs.map((v) => (bool ? String(v !== 0) : num(v)));
    lines.push(`${u.name} = ${text.length === 1 ? text[0] : `[${text.join(', ')}]`}`);
  }
  return lines.join('\n') + '\n';
}

function exportTres() {
  const lines = ['[gd_resource type="ShaderMaterial" load_steps=2 format=3]', '',
    `[ext_resource type="Shader" path="${st.shader_res || `res://${st.name}.gdshader`}" id="1"]`, '', '[resource]', 'shader = ExtResource("1")'];
  for (const u of uniforms()) {
    const vs = readUniform(u).map(num), kind = scalar(u.type), color = u.hints.some((h) => h.name === 'source_color');
    let text;
    if (kind === 'bool') text = vs.map((v) => (Number(v) ? 'true' : 'false')).join(', ');
    else if (vs.length === 1) text = vs[0];
    else if (color) text = `Color(${[...vs, ...(vs.length === 3 ? ['1'] : [])].join(', ')})`;
    else text = `Vector${vs.length}${kind === 'float' ? '' : 'i'}(${vs.join(', ')})`;
    lines.push(`shader_parameter/${u.name} = ${text}`);
  }
  return lines.join('\n') + '\n';
}

// --- hooks for tests and scripts ------------------------------------------------------------------

Object.assign(G, {
  setUniform,
  setScene(patch) { Object.assign(scene, patch); if (patch.sun) Object.assign(scene.lights[0], patch.sun); dirty = true; },
  exportFlags, exportToml, exportTres, compare,
  // Replaces a texture as a dropped file does: `bytes` an encoded image (PNG, JPEG, WebP).
  replaceTexture(name, bytes) {
    const slot = st.reflection.bindings.textures.find((t) => t.name === name);
    if (!slot) throw new Error(`no texture \`${name}\``);
    return replaceTexture(slot, new Blob([new Uint8Array(bytes)]));
  },
  // Resolves with the next frame rendered after the call.
  async nextFrame() {
    const start = G.frames;
    dirty = true;
    while (G.frames <= start || busy) await new Promise((r) => setTimeout(r, 10));
    return { width: G.width, height: G.height };
  },
  // Compiles WGSL with this browser's WebGPU (Tint in Chromium) and builds a pipeline for each
  // fragment entry with an automatic layout: the messages and the first error, if any.
  async validate(code, vertex, fragments) {
    device.pushErrorScope('validation');
    const module = device.createShaderModule({ code });
    const info = await module.getCompilationInfo();
    const messages = info.messages.map((m) => `${m.type} ${m.lineNum}:${m.linePos}: ${m.message}`);
    let pipelineError = null;
    if (!info.messages.some((m) => m.type === 'error')) {
      for (const entry of fragments) {
        try {
          await device.createRenderPipelineAsync({ layout: 'auto', vertex: { module, entryPoint: vertex },
            fragment: { module, entryPoint: entry, targets: [{ format: 'rgba32float' }] } });
        } catch (e) { pipelineError = pipelineError || `${entry}: ${e.message}`; }
      }
    }
    const scoped = await device.popErrorScope();
    return { messages, error: messages.find((m) => m.startsWith('error')) || pipelineError || (scoped && scoped.message) || null };
  },
});

Object.defineProperty(G, 'scene', { get: () => scene });

init().catch((e) => { G.error = String(e.message || e); showError(G.error); status('failed'); });
