#!/usr/bin/env node
// meshopt_js: the fidelity anchor of the benchmark, meshoptimizer's own JavaScript
// simplifier (npm meshoptimizer, pinned in peers/npm/package-lock.json; `npm ci --prefix
// scripts/bench/peers/npm` installs it).
//
//   node meshopt_js.mjs IN.ply (--targets N,N,.. | --fractions F,F,..) [-o PREFIX]
//        [--functions update,simplify] [--target-error E] [--flags Prune,..|none]
//
// Reads IN.ply (ascii or binary, either byte order; extra vertex properties and other
// elements are skipped; polygons are cut into fans), welds vertices at exactly equal
// positions (generatePositionRemap: meshoptimizer collapses along shared vertices only;
// nothing else is merged), then per target triangle count runs, from the full welded
// mesh each time, MeshoptSimplifier.simplifyWithUpdate ("update": vertices moved to
// their quadrics' optimum, no attributes) and MeshoptSimplifier.simplify ("simplify":
// the input's vertices kept), each call timed on its own. Defaults: flags ['Prune']
// (isolated parts may go whole, as meshoptimizer recommends for whole meshes) and
// target_error 1e10 (relative to the mesh extent: no limit), so a level stops above
// its target only where the topology allows no further collapse ("reached": false).
// With -o, each level is written as binary PLY PREFIX_<function>_<target>.ply
// (positions only, unused vertices dropped).
//
// stdout: one JSON object {"peer","version","input","input_triangles","input_vertices",
// "welded_vertices","read_seconds","weld_seconds","target_error","flags","levels":
// [{"function","target","triangles","reached","result_error","seconds","output"}],
// "peak_rss_kb"}. Exit 64 on usage errors, 65 when the input cannot be read, 74 when a
// write fails.
import { readFileSync, writeFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';

const here = fileURLToPath(new URL('.', import.meta.url));
const pkg = process.env.SCANLOD_MESHOPT_JS || here + 'npm/node_modules/meshoptimizer/';

function fail(code, msg) {
  process.stderr.write('meshopt_js: ' + msg + '\n');
  process.exit(code);
}

function usage(why) {
  fail(64, (why ? why + '\n' : '') +
    'usage: node meshopt_js.mjs IN.ply (--targets N,N,.. | --fractions F,F,..) [-o PREFIX]\n' +
    '         [--functions update,simplify] [--target-error E] [--flags Prune,..|none]');
}

function parseArgs(argv) {
  const o = { input: null, prefix: null, targets: null, fractions: false,
              functions: ['update', 'simplify'], targetError: 1e10, flags: ['Prune'] };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i], hasValue = i + 1 < argv.length;
    if ((a === '--targets' || a === '--fractions') && hasValue) {
      if (o.targets) usage('give --targets or --fractions once');
      o.fractions = a === '--fractions';
      o.targets = argv[++i].split(',').map(Number);
      const bad = o.targets.some(v => !(v > 0) ||
        (o.fractions ? v > 1 : !Number.isInteger(v)));
      if (!o.targets.length || bad)
        usage('bad list: whole counts for --targets, (0, 1] for --fractions');
    } else if (a === '-o' && hasValue) {
      o.prefix = argv[++i];
    } else if (a === '--functions' && hasValue) {
      o.functions = argv[++i].split(',');
      if (!o.functions.length || o.functions.some(f => f !== 'update' && f !== 'simplify'))
        usage('--functions takes update and/or simplify');
    } else if (a === '--target-error' && hasValue) {
      o.targetError = Number(argv[++i]);
      if (!(o.targetError > 0) || !Number.isFinite(o.targetError))
        usage('--target-error must be positive');
    } else if (a === '--flags' && hasValue) {
      const v = argv[++i];
      o.flags = v === 'none' ? [] : v.split(',');
    } else if (!a.startsWith('-') && !o.input) {
      o.input = a;
    } else {
      usage(null);
    }
  }
  if (!o.input || !o.targets) usage('needs an input and targets');
  return o;
}

// --- PLY reading ----------------------------------------------------------------------
const TYPES = {
  char: ['Int8', 1], int8: ['Int8', 1], uchar: ['Uint8', 1], uint8: ['Uint8', 1],
  short: ['Int16', 2], int16: ['Int16', 2], ushort: ['Uint16', 2], uint16: ['Uint16', 2],
  int: ['Int32', 4], int32: ['Int32', 4], uint: ['Uint32', 4], uint32: ['Uint32', 4],
  float: ['Float32', 4], float32: ['Float32', 4], double: ['Float64', 8], float64: ['Float64', 8],
};

function parseHeader(buf) {
  const at = buf.indexOf('end_header');
  if (buf.subarray(0, 4).toString('latin1') !== 'ply\n' &&
      buf.subarray(0, 5).toString('latin1') !== 'ply\r\n') throw new Error('not a PLY file');
  if (at < 0) throw new Error('no end_header');
  let body = at + 'end_header'.length;
  if (buf[body] === 13) body++;
  if (buf[body] !== 10) throw new Error('bad end_header line');
  body++;
  const h = { format: null, elements: [], body };
  for (const raw of buf.subarray(0, at).toString('latin1').split('\n')) {
    const w = raw.trim().split(/\s+/);
    if (w[0] === 'format') {
      h.format = w[1];
    } else if (w[0] === 'element') {
      h.elements.push({ name: w[1], count: Number(w[2]), props: [] });
    } else if (w[0] === 'property') {
      const el = h.elements[h.elements.length - 1];
      if (!el) throw new Error('property before any element');
      const p = w[1] === 'list'
        ? { list: true, countType: TYPES[w[2]], type: TYPES[w[3]], name: w[4] }
        : { list: false, type: TYPES[w[1]], name: w[2] };
      if (!p.type || (p.list && !p.countType)) throw new Error('unknown type in "' + raw.trim() + '"');
      el.props.push(p);
    }
  }
  if (!['ascii', 'binary_little_endian', 'binary_big_endian'].includes(h.format))
    throw new Error('unknown format ' + h.format);
  for (const el of h.elements)
    if (!Number.isInteger(el.count) || el.count < 0) throw new Error('bad count of ' + el.name);
  return h;
}

// Calls visit(element, values) per row; values[k] is a number or an array (list).
function readRows(buf, h, visit) {
  if (h.format === 'ascii') {
    const tok = buf.subarray(h.body).toString('latin1').split(/\s+/).filter(s => s.length);
    let t = 0;
    const next = () => {
      if (t >= tok.length) throw new Error('file ends early');
      const v = Number(tok[t++]);
      if (Number.isNaN(v) && !/^[-+]?nan$/i.test(tok[t - 1])) throw new Error('bad number ' + tok[t - 1]);
      return v;
    };
    for (const el of h.elements)
      for (let r = 0; r < el.count; r++)
        visit(el, el.props.map(p => {
          if (!p.list) return next();
          const n = next(), out = new Array(n);
          for (let k = 0; k < n; k++) out[k] = next();
          return out;
        }));
    return;
  }
  const le = h.format === 'binary_little_endian';
  const dv = new DataView(buf.buffer, buf.byteOffset, buf.byteLength);
  let off = h.body;
  const get = ([kind, size]) => {
    if (off + size > buf.byteLength) throw new Error('file ends early');
    const v = dv['get' + kind](off, le);
    off += size;
    return v;
  };
  for (const el of h.elements)
    for (let r = 0; r < el.count; r++)
      visit(el, el.props.map(p => {
        if (!p.list) return get(p.type);
        const n = get(p.countType), out = new Array(n);
        for (let k = 0; k < n; k++) out[k] = get(p.type);
        return out;
      }));
}

function readPly(path) {
  const buf = readFileSync(path);
  const h = parseHeader(buf);
  const vel = h.elements.find(e => e.name === 'vertex');
  const fel = h.elements.find(e => e.name === 'face');
  if (!vel || !fel) throw new Error('needs vertex and face elements');
  const axis = ['x', 'y', 'z'].map(n => vel.props.findIndex(p => p.name === n && !p.list));
  const list = fel.props.findIndex(p => p.list &&
    (p.name === 'vertex_indices' || p.name === 'vertex_index'));
  if (axis.includes(-1)) throw new Error('vertex element without x, y, z');
  if (list < 0) throw new Error('face element without vertex_indices');
  const positions = new Float32Array(3 * vel.count);
  let tri = new Uint32Array(3 * fel.count), nt = 0, v = 0, polygons = 0;
  readRows(buf, h, (el, row) => {
    if (el === vel) {
      for (let k = 0; k < 3; k++) positions[3 * v + k] = row[axis[k]];
      v++;
    } else if (el === fel) {
      const f = row[list];
      if (f.length > 3) polygons++;
      for (let k = 2; k < f.length; k++) {   // a fan; fewer than 3 corners: nothing
        if (nt + 3 > tri.length) {
          const grown = new Uint32Array(2 * tri.length + 3);
          grown.set(tri);
          tri = grown;
        }
        for (const i of [f[0], f[k - 1], f[k]]) {
          if (!Number.isInteger(i) || i < 0 || i >= vel.count)
            throw new Error('face index ' + i + ' out of range');
          tri[nt++] = i;
        }
      }
    }
  });
  const indices = tri.subarray(0, nt);
  for (const i of indices)
    for (let k = 0; k < 3; k++)
      if (!Number.isFinite(positions[3 * i + k])) throw new Error('non-finite coordinate on vertex ' + i);
  if (!indices.length) throw new Error('no triangles');
  return { positions, indices, vertices: vel.count, polygons };
}

// --- PLY writing ----------------------------------------------------------------------
function writePly(path, positions, indices) {
  const nv = positions.length / 3, nf = indices.length / 3;
  const head = Buffer.from('ply\nformat binary_little_endian 1.0\ncomment meshopt_js\n' +
    'element vertex ' + nv + '\nproperty float x\nproperty float y\nproperty float z\n' +
    'element face ' + nf + '\nproperty list uchar int vertex_indices\nend_header\n', 'latin1');
  const body = Buffer.alloc(12 * nv + 13 * nf);
  for (let i = 0; i < 3 * nv; i++) body.writeFloatLE(positions[i], 4 * i);
  let off = 12 * nv;
  for (let f = 0; f < nf; f++) {
    body[off++] = 3;
    for (let k = 0; k < 3; k++, off += 4) body.writeInt32LE(indices[3 * f + k], off);
  }
  writeFileSync(path, Buffer.concat([head, body]));
}

// The level's indices (into positions) as a compact mesh: unused vertices dropped.
function compact(S, positions, indices) {
  const idx = new Uint32Array(indices);
  const [remap, unique] = S.compactMesh(idx);
  const out = new Float32Array(3 * unique);
  for (let v = 0; v < remap.length; v++)
    if (remap[v] !== 0xffffffff)
      for (let k = 0; k < 3; k++) out[3 * remap[v] + k] = positions[3 * v + k];
  return [out, idx];
}

// --- main -----------------------------------------------------------------------------
const o = parseArgs(process.argv.slice(2));
const { MeshoptSimplifier: S } = await import(pkg + 'meshopt_simplifier.js');
const version = JSON.parse(readFileSync(pkg + 'package.json', 'utf8')).version;
await S.ready;

let t0 = performance.now();
let mesh;
try {
  mesh = readPly(o.input);
} catch (e) {
  fail(65, o.input + ': ' + e.message);
}
const readSeconds = (performance.now() - t0) / 1e3;

t0 = performance.now();
const remap = S.generatePositionRemap(mesh.positions, 3);
const welded = new Uint32Array(mesh.indices.length);
for (let i = 0; i < welded.length; i++) welded[i] = remap[mesh.indices[i]];
let weldedVertices = 0;
for (let v = 0; v < remap.length; v++) if (remap[v] === v) weldedVertices++;
const weldSeconds = (performance.now() - t0) / 1e3;

const inputTriangles = welded.length / 3;
const levels = [];
for (const value of o.targets) {
  const target = o.fractions ? Math.round(value * inputTriangles) : value;
  const goal = 3 * Math.min(target, inputTriangles);
  for (const fn of o.functions) {
    let indices, positions, error;
    const t = performance.now();
    if (fn === 'update') {
      indices = new Uint32Array(welded);
      positions = new Float32Array(mesh.positions);
      const [count, err] = S.simplifyWithUpdate(indices, positions, 3, new Float32Array(0), 0,
                                                [], null, goal, o.targetError, o.flags);
      indices = indices.subarray(0, count);
      error = err;
    } else {
      positions = mesh.positions;
      [indices, error] = S.simplify(welded, positions, 3, goal, o.targetError, o.flags);
    }
    const seconds = (performance.now() - t) / 1e3;
    let output = null;
    if (o.prefix) {
      output = o.prefix + '_' + fn + '_' + target + '.ply';
      try {
        const [p, i] = compact(S, positions, indices);
        writePly(output, p, i);
      } catch (e) {
        fail(74, output + ': ' + e.message);
      }
    }
    levels.push({ function: fn === 'update' ? 'simplifyWithUpdate' : 'simplify', target,
                  triangles: indices.length / 3, reached: indices.length / 3 <= target,
                  result_error: error, seconds, output });
  }
}
process.stdout.write(JSON.stringify({
  peer: 'meshoptimizer-js', version, input: o.input, input_triangles: inputTriangles,
  input_vertices: mesh.vertices, welded_vertices: weldedVertices,
  polygons_triangulated: mesh.polygons, read_seconds: readSeconds, weld_seconds: weldSeconds,
  target_error: o.targetError, flags: o.flags, levels,
  peak_rss_kb: process.resourceUsage().maxRSS,
}) + '\n');
