// meshflow's viewer page: receives meshes in meshflow's own codec over the WebSocket of the
// server that served the page (serve/server.h documents the messages), decodes them with the C++
// decoder compiled to WebAssembly (web/mfc_decoder.cpp over nodes/compress), and shows them with
// three.js (Debian's libjs-three, served by meshflow). A progressive mesh is shown from its base
// level on; each chunk of vertex-split packets refines it. A run (meshflow run/live/reconstruct
// --serve) sends its newest mesh and stats as it goes; {"type":"end"} says the run is over and
// everything it published has arrived: the page's state becomes "complete" once that mesh is
// shown in full.

import * as THREE from '/three/build/three.module.js';
import { OrbitControls } from '/three/examples/jsm/controls/OrbitControls.js';
import createDecoder from '/mfc_decoder.js';

const $ = (id) => document.getElementById(id);

// The page's own timeline (data-timeline, for bench/serve/serve_bench.py): "ms event" entries,
// milliseconds since the WebSocket opened, the first 400 of them: each message's arrival and
// size, each decode and draw with its duration.
const timeline = [];
let timelineStart = performance.now();
function note(event) {
  if (timeline.length >= 400) return;
  timeline.push(`${(performance.now() - timelineStart).toFixed(1)} ${event}`);
  document.body.dataset.timeline = timeline.join(';');
}

function setState(state) {
  document.body.dataset.state = state;
  $('state').textContent = state;
}

function fail(message) {
  setState('error');
  $('error').textContent = message;
  document.body.dataset.error = message;  // for the browser tests
}

// --- three.js scene --------------------------------------------------------------------------
let renderer = null;
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x20242a);
const camera = new THREE.PerspectiveCamera(45, window.innerWidth / window.innerHeight, 0.001, 1e4);
camera.position.set(0, 0, 3);
scene.add(camera);
scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 0.6));
const headlight = new THREE.DirectionalLight(0xffffff, 0.7);
headlight.position.set(0.3, 0.5, 1);
camera.add(headlight);
let controls = null;
try {
  renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(window.innerWidth, window.innerHeight);
  $('view').appendChild(renderer.domElement);
  controls = new OrbitControls(camera, renderer.domElement);
  document.body.dataset.webgl = 'yes';
} catch (e) {
  document.body.dataset.webgl = 'no';
  $('error').textContent = 'no WebGL: ' + e.message;
}
// Lambert (lit per vertex) and no multisampling: a software renderer (a GPU-less machine, the
// headless tests) drew a whole fused Redwood map's 1408 blocks faster than with the physically
// based material and 4x MSAA (bench/RESULTS.md, "Viewing").
const material = new THREE.MeshLambertMaterial({ color: 0xb8c4d0, side: THREE.DoubleSide });
let mesh = null;
let fitted = false;  // the camera is fitted to the first mesh only (a run's frames keep the view)
// The camera was last fitted to a growing map's blocks: the whole mesh that replaces them (a
// fused run's final one) is fitted again, unless the user moved the camera. (The blocks can
// arrive before the final mesh is decoded; the view then framed only the first blocks.)
let fittedToBlocks = false;
let ended = false;   // the server said nothing more will come
let userMoved = false;  // the camera follows a growing map until the user moves it
// A fused map's blocks (see onBlocks).
const blockGroup = new THREE.Group();
scene.add(blockGroup);
const blocks = new Map();       // "x,y,z" -> { object, interior, shared: [edge], triangles }
const sharedEdges = new Map();  // global edge "gx,gy,gz,axis" -> blocks that list it
let blockInterior = 0;
let blockTriangles = 0;
const blockBox = new THREE.Box3();  // every block's box so far (grows only)

// Drawing: render() draws now; requestRender() draws soon, at most a quarter of the time. A
// fused map arrives as many batches of blocks, and with a software renderer (a GPU-less
// machine, the headless tests) one draw of a whole Redwood map took 0.1-0.3 s: drawing after
// every batch spent most of the map's load drawing pictures nobody saw.
let renderTimer = null;
let lastRenderEnd = 0;
let lastRenderMs = 0;
const shownWaiting = [];  // map_shown messages whose blocks are in the scene, not yet drawn
const roundsWaiting = [];  // map rounds applied, to acknowledge once drawn

// Flow control (serve/server.h: map_round): the server sends the next round of blocks only
// after this page says it has applied and drawn the last, so nothing piles up in the socket
// and a map update waits for at most about one decode and draw.
function acknowledgeRounds() {
  for (const round of roundsWaiting) {
    if (socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify({ type: 'map_ack', round }));
  }
  roundsWaiting.length = 0;
}

function render() {
  if (renderTimer !== null) {
    clearTimeout(renderTimer);
    renderTimer = null;
  }
  if (!renderer) return acknowledgeRounds();
  const t0 = performance.now();
  renderer.render(scene, camera);
  const t1 = performance.now();
  note(`draw ${(t1 - t0).toFixed(1)}`);
  lastRenderEnd = t1;
  lastRenderMs = t1 - t0;
  const d = document.body.dataset;
  d.renders = Number(d.renders || 0) + 1;
  d.renderMs = (Number(d.renderMs || 0) + lastRenderMs).toFixed(1);
  if (shownWaiting.length > 0) recordShown(performance.timeOrigin + t1);
  acknowledgeRounds();
}

function requestRender() {
  if (renderTimer !== null) return;
  const wait = Math.max(0, lastRenderEnd + 3 * lastRenderMs - performance.now());
  renderTimer = setTimeout(render, wait);
}

// The live map's latency (serve/map_publisher.h: map_shown): for each frame a drawn update
// holds, the time from the frame entering the run's graph to this page having drawn it, both
// in milliseconds of this machine's clock (performance.timeOrigin + now(): the Unix epoch).
// data-map-latencies lists "seq:entered:total:server" per frame (ms): entered (epoch), total =
// entered to drawn, server = entered to published (meshed and coded), the rest being the link
// and this page; bench/serve/serve_bench.py reads it.
function recordShown(drawnEpochMs) {
  const d = document.body.dataset;
  const rows = d.mapLatencies ? [d.mapLatencies] : [];
  for (const m of shownWaiting) {
    for (const [seq, entered] of m.frames) {
      rows.push(`${seq}:${entered.toFixed(1)}:${(drawnEpochMs - entered).toFixed(1)}:` +
                `${(m.published_ms - entered).toFixed(1)}`);
    }
  }
  shownWaiting.length = 0;
  d.mapLatencies = rows.join(',');
}
if (controls) {
  controls.addEventListener('change', requestRender);
  controls.addEventListener('start', () => { userMoved = true; });
}
window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  if (renderer) renderer.setSize(window.innerWidth, window.innerHeight);
  render();
});
$('wireframe').addEventListener('change', (e) => { material.wireframe = e.target.checked; render(); });
$('colors').addEventListener('change', () => { applyColors(); render(); });

// Only a change of the colour mode marks the material for an update: each update recompiles its
// shaders, which a software renderer takes a second or more for (a fused map's every batch of
// blocks, or a run's every mesh, used to pay it).
function applyColors() {
  const has = (mesh && mesh.geometry.getAttribute('color') !== undefined) || blocks.size > 0;
  const mode = has && $('colors').checked ? THREE.VertexColors : THREE.NoColors;
  material.color.set(mode === THREE.VertexColors ? 0xffffff : 0xb8c4d0);
  if (material.vertexColors === mode) return;
  material.vertexColors = mode;
  material.needsUpdate = true;
  document.body.dataset.materialUpdates = Number(document.body.dataset.materialUpdates || 0) + 1;
}

// --- the decoder (WebAssembly) ---------------------------------------------------------------
const decoder = await createDecoder();

// The material's shader programs, with and without vertex colours, are compiled now, before the
// stream starts: a first draw compiles them, which takes a software renderer (a GPU-less
// machine, the headless tests) a second or more that would otherwise delay the first picture.
// (Drawing here instead, to have the GPU process build its routines too, made it worse: after
// a draw headless Chromium holds the page's WebSocket messages back for a second or more, so the
// stream arrived before the page could show its base.)
if (renderer) {
  const t0 = performance.now();
  const warm = new THREE.BufferGeometry();
  warm.setAttribute('position', new THREE.BufferAttribute(new Float32Array(9), 3));
  warm.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(9), 3));
  warm.setAttribute('color', new THREE.BufferAttribute(new Uint8Array(9), 3, true));
  const warmMesh = new THREE.Mesh(warm, material);
  scene.add(warmMesh);
  for (const colors of [THREE.NoColors, THREE.VertexColors]) {
    material.vertexColors = colors;
    material.needsUpdate = true;
    renderer.compile(scene, camera);
  }
  material.vertexColors = THREE.NoColors;
  material.needsUpdate = true;
  scene.remove(warmMesh);
  warm.dispose();
  document.body.dataset.warmMs = (performance.now() - t0).toFixed(1);
}

// Decodes data[0, size) (a complete image when packets < 0, else a progressive prefix holding
// the base and `packets` split packets) into a BufferGeometry, or throws.
function decode(data, size, baseEnd, packets) {
  const ptr = decoder._malloc(size);
  decoder.HEAPU8.set(data.subarray(0, size), ptr);
  const t0 = performance.now();
  const rc = decoder._mf_decode(ptr, size, baseEnd, packets);
  const ms = performance.now() - t0;
  if (packets >= 0 || size > 65536) note(`decode ${size} B ${ms.toFixed(1)}`);
  decoder._free(ptr);
  // The page's own profile (bench/serve/serve_bench.py reads it): decodes and their time.
  document.body.dataset.decodes = Number(document.body.dataset.decodes || 0) + 1;
  document.body.dataset.decodeMs = (Number(document.body.dataset.decodeMs || 0) + ms).toFixed(1);
  if (rc !== 0) throw new Error(decoder.UTF8ToString(decoder._mf_error()));
  const nv = decoder._mf_vertex_count();
  const nt = decoder._mf_triangle_count();
  const heap = decoder.HEAPU8.buffer;  // after the call: memory may have grown
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(
      new Float32Array(heap, decoder._mf_positions(), 3 * nv).slice(), 3));
  geometry.setIndex(new THREE.BufferAttribute(
      new Uint32Array(heap, decoder._mf_indices(), 3 * nt).slice(), 1));
  const normals = decoder._mf_normals();
  if (normals) {
    geometry.setAttribute('normal', new THREE.BufferAttribute(
        new Float32Array(heap, normals, 3 * nv).slice(), 3));
  } else {
    geometry.computeVertexNormals();
  }
  const colors = decoder._mf_colors();
  if (colors) {
    geometry.setAttribute('color', new THREE.BufferAttribute(
        new Uint8Array(heap, colors, 3 * nv).slice(), 3, true));
  }
  return { geometry, vertices: nv, triangles: nt, ms };
}

// --- the stream --------------------------------------------------------------------------------
// { header, data: Uint8Array, received, shownPrefix, complete, and with "refine":"single_rate"
//   single: Uint8Array, singleReceived }
let current = null;
let bytesReceived = 0;
let openedAt = 0;
let decodeQueued = false;
// A level is decoded from the start each time (the decoder keeps no state between calls), so
// finer levels are decoded no more often than every two decodes' time: on a fast link the chunks
// then go straight to the full mesh instead of the decoder working through every level
// (bench/serve/serve_bench.py measures both). The first picture and the full mesh never wait.
let lastDecodeEnd = 0;
let lastDecodeMs = 0;

function show(result, header, level) {
  if (mesh) {
    scene.remove(mesh);
    mesh.geometry.dispose();
  }
  mesh = new THREE.Mesh(result.geometry, material);
  scene.add(mesh);
  applyColors();
  blockGroup.visible = false;  // a whole mesh (a fused run's final one) replaces the blocks
  if (!fitted || (fittedToBlocks && !userMoved)) {
    result.geometry.computeBoundingSphere();
    fitCamera(result.geometry.boundingSphere);
    fittedToBlocks = false;
  }
  showCounts(result.vertices, result.triangles, level);
  $('decode-ms').textContent = result.ms.toFixed(1) + ' ms';
  render();
}

// The whole bounding sphere in view, with a margin, seen from above and in front; once.
function fitCamera({ center, radius }) {
  fitted = true;
  const r = Math.max(radius, 1e-6);
  camera.near = r / 100;
  camera.far = r * 100;
  const distance = 1.3 * r / Math.sin((camera.fov / 2) * Math.PI / 180);
  const direction = new THREE.Vector3(0.35, 0.45, 0.82).normalize();
  camera.position.copy(center).addScaledVector(direction, distance);
  camera.updateProjectionMatrix();
  if (controls) {
    controls.target.copy(center);
    controls.update();
  }
  if (document.body.dataset.firstMs) return;
  const first = performance.now() - openedAt;
  $('first-ms').textContent = first.toFixed(0) + ' ms';
  document.body.dataset.firstMs = first.toFixed(1);  // for bench/serve/serve_bench.py
}

function showCounts(vertices, triangles, level) {
  $('triangles').textContent = triangles;
  $('vertices').textContent = vertices;
  $('level').textContent = level;
  document.body.dataset.levels = Number(document.body.dataset.levels || 0) + 1;
  document.body.dataset.triangles = triangles;
  document.body.dataset.vertices = vertices;
}

// --- a fused map, block by block (serve/map_publisher.h: the payload) --------------------------
// Each block is its own three.js mesh; vertices on edges that neighbouring blocks share are
// listed by global grid edge, so the counts are those of the welded map (TsdfMesher::extract()).

function globalEdge(x, y, z, code) {
  const axis = code % 3;
  let rest = (code - axis) / 3;
  const lz = rest % 9;
  rest = (rest - lz) / 9;
  const ly = rest % 9;
  const lx = (rest - ly) / 9;
  return `${8 * x + lx},${8 * y + ly},${8 * z + lz},${axis}`;
}

function removeBlock(key) {
  const b = blocks.get(key);
  if (!b) return;
  blockGroup.remove(b.object);
  b.object.geometry.dispose();
  blockInterior -= b.interior;
  blockTriangles -= b.triangles;
  for (const e of b.shared) {
    const n = sharedEdges.get(e) - 1;
    if (n === 0) sharedEdges.delete(e); else sharedEdges.set(e, n);
  }
  blocks.delete(key);
}

// A batch: u32 0, u32 count, then per block i32 x, y, z, u32 n, n payload bytes.
function onBlocks(buffer) {
  const view = new DataView(buffer);
  const count = view.getUint32(4, true);
  let at = 8;
  let ms = 0;
  try {
    for (let i = 0; i < count; ++i) {
      const x = view.getInt32(at, true), y = view.getInt32(at + 4, true);
      const z = view.getInt32(at + 8, true), n = view.getUint32(at + 12, true);
      at += 16;
      if (at + n > buffer.byteLength) throw new Error('a block past the batch\'s end');
      const key = `${x},${y},${z}`;
      removeBlock(key);
      if (n > 0) {
        const s = view.getUint16(at, true);
        const mfcAt = at + 2 + 4 * s;
        const bytes = new Uint8Array(buffer, mfcAt, at + n - mfcAt);
        const result = decode(bytes, bytes.length, 0, -1);
        ms += result.ms;
        const shared = [];
        for (let k = 0; k < s; ++k) {
          shared.push(globalEdge(x, y, z, view.getUint16(at + 2 + 4 * k + 2, true)));
        }
        for (const e of shared) sharedEdges.set(e, (sharedEdges.get(e) || 0) + 1);
        result.geometry.computeBoundingBox();
        blockBox.union(result.geometry.boundingBox);
        const object = new THREE.Mesh(result.geometry, material);
        object.matrixAutoUpdate = false;  // blocks stay where they are (world coordinates)
        blockGroup.add(object);
        blocks.set(key, { object, interior: result.vertices - s, shared, triangles: result.triangles });
        blockInterior += result.vertices - s;
        blockTriangles += result.triangles;
      }
      at += n;
    }
  } catch (e) {
    return fail('block: ' + e.message);
  }
  document.body.dataset.blocks = blocks.size;
  if (mesh) return;  // a whole mesh is shown: the blocks stay hidden
  if (!userMoved && blocks.size > 0) {
    fitCamera(blockBox.getBoundingSphere(new THREE.Sphere()));
    fittedToBlocks = true;
  }
  applyColors();
  showCounts(blockInterior + sharedEdges.size, blockTriangles, `map: ${blocks.size} blocks`);
  $('decode-ms').textContent = ms.toFixed(1) + ' ms';
  if (document.body.dataset.state !== 'complete') setState('shown');
  requestRender();
}

// The whole mesh: its progressive image complete, or its single-rate image (after the base).
function fullImage(c) {
  if (c.single) return c.singleReceived === c.single.length ? c.single : null;
  return c.received === c.header.bytes ? c.data : null;
}

function decodeLatest() {
  decodeQueued = false;
  const c = current;
  if (!c) return;
  const h = c.header;
  try {
    const whole = fullImage(c);
    if (whole) {
      if (c.complete) return;
      c.complete = true;
      const t0 = performance.now();
      const result = decode(whole, whole.length, 0, -1);
      const t1 = performance.now();
      show(result, h, 'full');
      document.body.dataset.fullDecodeMs = (t1 - t0).toFixed(1);
      document.body.dataset.fullShowMs = (performance.now() - t1).toFixed(1);
      const full = performance.now() - openedAt;
      $('full-ms').textContent = full.toFixed(0) + ' ms';
      document.body.dataset.fullMs = full.toFixed(1);
      document.body.dataset.meshes = Number(document.body.dataset.meshes || 0) + 1;
      setState(ended ? 'complete' : 'shown');
      return;
    }
    if (h.kind !== 'progressive' || c.received < h.base_end) return;
    if (c.single && c.shownPrefix > 0) return;  // the base is shown; the full mesh comes whole
    let packets = 0;
    while (packets < h.packet_ends.length && h.packet_ends[packets] <= c.received) ++packets;
    // Every packet in but not the file's end (its last bytes in a later chunk): the decoder would
    // read the missing end; the whole image is decoded once it arrives.
    if (packets === h.packet_ends.length) return;
    const prefix = packets === 0 ? h.base_end : h.packet_ends[packets - 1];
    if (prefix <= c.shownPrefix) return;
    const wait = lastDecodeEnd + 2 * lastDecodeMs - performance.now();
    if (c.shownPrefix > 0 && wait > 0) {
      decodeQueued = true;
      setTimeout(decodeLatest, wait);
      return;
    }
    c.shownPrefix = prefix;
    const result = decode(c.data, prefix, h.base_end, packets);
    lastDecodeEnd = performance.now();
    lastDecodeMs = result.ms;
    show(result, h, `${packets} / ${h.packet_ends.length} packets`);
  } catch (e) {
    fail('decode: ' + e.message);
  }
}

function onText(text) {
  const message = JSON.parse(text);
  if (message.type === 'mesh') {
    current = { header: message, data: new Uint8Array(message.bytes), received: 0, shownPrefix: 0,
                complete: false };
    document.body.dataset.refine = message.refine || 'packets';
    if (message.refine === 'single_rate') {
      current.single = new Uint8Array(message.single_rate_bytes);
      current.singleReceived = 0;
    }
    setState('streaming');
  } else if (message.type === 'stats') {
    const rows = [];
    for (const [stage, ms] of Object.entries(message.stages_ms || {})) {
      rows.push(`<tr><td>${stage}</td><td>${Number(ms).toFixed(1)} ms</td></tr>`);
    }
    if (rows.length > 0) $('stages').innerHTML = rows.join('');
    if (message.source) $('source').textContent = message.source;
    if (message.frames !== undefined) {
      $('frames').textContent = message.frames;
      document.body.dataset.frames = message.frames;
    }
    if (message.frames_per_second !== undefined) {
      $('fps').textContent = Number(message.frames_per_second).toFixed(1);
    }
    if (message.state === 'finished') document.body.dataset.run = 'finished';
  } else if (message.type === 'map_shown') {
    // Its blocks came before it and are in the scene: the next draw shows them.
    shownWaiting.push(message);
    requestRender();
  } else if (message.type === 'map_round') {
    // Its blocks are in the scene: acknowledged after the next draw.
    roundsWaiting.push(message.round);
    document.body.dataset.mapRounds = message.round;
    requestRender();
  } else if (message.type === 'end') {
    ended = true;
    const c = current;
    if (document.body.dataset.state === 'error') return;
    if (!c || c.complete) {
      if (renderTimer !== null) render();  // the last blocks drawn before saying so
      if (!c && blocks.size > 0) {  // a fused map's blocks, all of them here
        document.body.dataset.fullMs = (performance.now() - openedAt).toFixed(1);
      }
      setState('complete');
    }
  }
}

function onBinary(buffer) {
  if (bytesReceived === 0) document.body.dataset.firstByteMs = (performance.now() - openedAt).toFixed(1);
  bytesReceived += buffer.byteLength;
  $('bytes').textContent = String(bytesReceived);  // (toLocaleString's first call took 0.25 s)
  document.body.dataset.bytes = bytesReceived;
  const view = new DataView(buffer);
  const id = view.getUint32(0, true);
  if (id === 0) return onBlocks(buffer);
  const offset = view.getUint32(4, true);
  const c = current;
  const chunk = new Uint8Array(buffer, 8);
  if (c && c.single && id === (c.header.id | 0x80000000) >>> 0) {
    // A chunk of the single-rate image that follows the base.
    if (c.singleReceived !== offset) return;
    if (offset + chunk.length > c.single.length) return fail('a chunk past the image\'s end');
    c.single.set(chunk, offset);
    c.singleReceived += chunk.length;
    if (c.singleReceived === c.single.length) {
      document.body.dataset.lastByteMs = (performance.now() - openedAt).toFixed(1);
      setTimeout(decodeLatest, 0);
    }
    return;
  }
  if (!c || c.header.id !== id || c.received !== offset) return;  // a stale mesh's chunk
  if (offset + chunk.length > c.header.bytes) return fail('a chunk past the mesh\'s end');
  c.data.set(chunk, offset);
  c.received += chunk.length;
  if (c.received === c.header.bytes) {
    document.body.dataset.lastByteMs = (performance.now() - openedAt).toFixed(1);
    setTimeout(decodeLatest, 0);  // the full mesh at once (a waiting level's timer then returns)
  } else if (!decodeQueued) {
    decodeQueued = true;
    setTimeout(decodeLatest, 0);  // several chunks in one task decode once
  }
}

const socket = new WebSocket(`ws://${location.host}/ws`);
socket.binaryType = 'arraybuffer';
socket.addEventListener('open', () => {
  openedAt = performance.now();
  timelineStart = openedAt;
  document.body.dataset.openedEpochMs = (performance.timeOrigin + openedAt).toFixed(1);
  note('open');
  setState('waiting');
  socket.send(JSON.stringify({ type: 'hello' }));
});
socket.addEventListener('message', (event) => {
  const t0 = performance.now();
  const text = typeof event.data === 'string';
  if (text) onText(event.data);
  else onBinary(event.data);
  note(`${text ? 'text' : 'binary'} ${text ? event.data.length : event.data.byteLength} B handled in ${(performance.now() - t0).toFixed(1)}`);
});
socket.addEventListener('close', () => {
  if (document.body.dataset.state !== 'complete') fail('connection closed');
});
