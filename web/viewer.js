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

function setState(state) {
  document.body.dataset.state = state;
  $('state').textContent = state;
}

function fail(message) {
  setState('error');
  $('error').textContent = message;
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
  renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(window.innerWidth, window.innerHeight);
  $('view').appendChild(renderer.domElement);
  controls = new OrbitControls(camera, renderer.domElement);
  document.body.dataset.webgl = 'yes';
} catch (e) {
  document.body.dataset.webgl = 'no';
  $('error').textContent = 'no WebGL: ' + e.message;
}
const material = new THREE.MeshStandardMaterial({
  color: 0xb8c4d0, roughness: 0.7, metalness: 0.0, side: THREE.DoubleSide,
});
let mesh = null;
let fitted = false;  // the camera is fitted to the first mesh only (a run's frames keep the view)
let ended = false;   // the server said nothing more will come

function render() {
  if (renderer) renderer.render(scene, camera);
}
if (controls) controls.addEventListener('change', render);
window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  if (renderer) renderer.setSize(window.innerWidth, window.innerHeight);
  render();
});
$('wireframe').addEventListener('change', (e) => { material.wireframe = e.target.checked; render(); });
$('colors').addEventListener('change', () => { applyColors(); render(); });

function applyColors() {
  const has = mesh && mesh.geometry.getAttribute('color') !== undefined;
  material.vertexColors = has && $('colors').checked ? THREE.VertexColors : THREE.NoColors;
  material.color.set(material.vertexColors === THREE.VertexColors ? 0xffffff : 0xb8c4d0);
  material.needsUpdate = true;
}

// --- the decoder (WebAssembly) ---------------------------------------------------------------
const decoder = await createDecoder();

// Decodes data[0, size) (a complete image when packets < 0, else a progressive prefix holding
// the base and `packets` split packets) into a BufferGeometry, or throws.
function decode(data, size, baseEnd, packets) {
  const ptr = decoder._malloc(size);
  decoder.HEAPU8.set(data.subarray(0, size), ptr);
  const t0 = performance.now();
  const rc = decoder._mf_decode(ptr, size, baseEnd, packets);
  const ms = performance.now() - t0;
  decoder._free(ptr);
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
let current = null;  // { header, data: Uint8Array, received, shownPrefix }
let bytesReceived = 0;
let openedAt = 0;
let decodeQueued = false;

function show(result, header, level) {
  if (mesh) {
    scene.remove(mesh);
    mesh.geometry.dispose();
  }
  mesh = new THREE.Mesh(result.geometry, material);
  scene.add(mesh);
  applyColors();
  if (!fitted) {
    fitted = true;
    result.geometry.computeBoundingSphere();
    const { center, radius } = result.geometry.boundingSphere;
    const r = Math.max(radius, 1e-6);
    camera.near = r / 100;
    camera.far = r * 100;
    // The whole bounding sphere in view, with a margin, seen from above and in front.
    const distance = 1.3 * r / Math.sin((camera.fov / 2) * Math.PI / 180);
    const direction = new THREE.Vector3(0.35, 0.45, 0.82).normalize();
    camera.position.copy(center).addScaledVector(direction, distance);
    camera.updateProjectionMatrix();
    if (controls) {
      controls.target.copy(center);
      controls.update();
    }
    $('first-ms').textContent = (performance.now() - openedAt).toFixed(0) + ' ms';
  }
  $('triangles').textContent = result.triangles;
  $('vertices').textContent = result.vertices;
  $('level').textContent = level;
  $('decode-ms').textContent = result.ms.toFixed(1) + ' ms';
  document.body.dataset.levels = Number(document.body.dataset.levels || 0) + 1;
  document.body.dataset.triangles = result.triangles;
  document.body.dataset.vertices = result.vertices;
  render();
}

function decodeLatest() {
  decodeQueued = false;
  const c = current;
  if (!c) return;
  const h = c.header;
  try {
    if (c.received === h.bytes) {
      if (c.shownPrefix === h.bytes) return;
      c.shownPrefix = h.bytes;
      show(decode(c.data, h.bytes, 0, -1), h, 'full');
      $('full-ms').textContent = (performance.now() - openedAt).toFixed(0) + ' ms';
      document.body.dataset.meshes = Number(document.body.dataset.meshes || 0) + 1;
      setState(ended ? 'complete' : 'shown');
      return;
    }
    if (h.kind !== 'progressive' || c.received < h.base_end) return;
    let packets = 0;
    while (packets < h.packet_ends.length && h.packet_ends[packets] <= c.received) ++packets;
    const prefix = packets === 0 ? h.base_end : h.packet_ends[packets - 1];
    if (prefix <= c.shownPrefix) return;
    c.shownPrefix = prefix;
    show(decode(c.data, prefix, h.base_end, packets), h,
         `${packets} / ${h.packet_ends.length} packets`);
  } catch (e) {
    fail('decode: ' + e.message);
  }
}

function onText(text) {
  const message = JSON.parse(text);
  if (message.type === 'mesh') {
    current = { header: message, data: new Uint8Array(message.bytes), received: 0, shownPrefix: 0 };
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
  } else if (message.type === 'end') {
    ended = true;
    const c = current;
    if (!c || (c.received === c.header.bytes && c.shownPrefix === c.header.bytes)) {
      setState('complete');
    }
  }
}

function onBinary(buffer) {
  bytesReceived += buffer.byteLength;
  $('bytes').textContent = bytesReceived.toLocaleString('en');
  const view = new DataView(buffer);
  const id = view.getUint32(0, true);
  const offset = view.getUint32(4, true);
  const c = current;
  if (!c || c.header.id !== id || c.received !== offset) return;  // a stale mesh's chunk
  const chunk = new Uint8Array(buffer, 8);
  if (offset + chunk.length > c.header.bytes) return fail('a chunk past the mesh\'s end');
  c.data.set(chunk, offset);
  c.received += chunk.length;
  if (!decodeQueued) {
    decodeQueued = true;
    setTimeout(decodeLatest, 0);  // several chunks in one task decode once
  }
}

const socket = new WebSocket(`ws://${location.host}/ws`);
socket.binaryType = 'arraybuffer';
socket.addEventListener('open', () => {
  openedAt = performance.now();
  setState('waiting');
  socket.send(JSON.stringify({ type: 'hello' }));
});
socket.addEventListener('message', (event) => {
  if (typeof event.data === 'string') onText(event.data);
  else onBinary(event.data);
});
socket.addEventListener('close', () => {
  if (document.body.dataset.state !== 'complete') fail('connection closed');
});
