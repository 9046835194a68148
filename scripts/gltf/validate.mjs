#!/usr/bin/env node
// Runs the Khronos glTF validator (npm `gltf-validator`, the official validator compiled to
// JS) over each FILE.glb given and prints one JSON line per file:
//   {"file":..., "numErrors":N, "numWarnings":N, "numInfos":N, "numHints":N, "issues":[...]}
// `issues` lists the errors and warnings (code, severity, pointer, message), at most 20.
// --infos: list the infos too (the compressed files' UNSUPPORTED_EXTENSION and
// UNUSED_OBJECT: the validator cannot look inside EXT_meshopt_compression or
// KHR_draco_mesh_compression streams, docs/glb.md).
// Exit status: 0 when no file has an error, 1 when some file has one, 2 on usage errors or
// an unreadable file. Warnings do not fail the run unless --strict is given, because a
// warning (e.g. an unused accessor) is valid glTF that every conforming viewer loads.
//
// Install once: `npm ci --prefix scripts/gltf` (scripts/install-deps.sh does it).
import { readFile } from 'node:fs/promises';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  console.error('validate.mjs: gltf-validator is not installed: ' +
                'run `npm ci --prefix scripts/gltf`');
  process.exit(2);
}

const args = process.argv.slice(2);
const strict = args.includes('--strict');
const infos = args.includes('--infos');
const files = args.filter((a) => a !== '--strict' && a !== '--infos');
if (files.length === 0) {
  console.error('usage: validate.mjs [--strict] [--infos] FILE.glb...');
  process.exit(2);
}

const SEVERITY = ['error', 'warning', 'info', 'hint'];
let failed = false;
let unreadable = false;
for (const file of files) {
  let bytes;
  try {
    bytes = new Uint8Array(await readFile(file));
  } catch (e) {
    console.error(`validate.mjs: ${file}: ${e.message}`);
    unreadable = true;
    continue;
  }
  let report;
  try {
    report = await validator.validateBytes(bytes, { uri: file, format: 'glb', maxIssues: 0,
                                                    writeTimestamp: false });
  } catch (e) {
    // A rejected promise means the validator could not even parse the container.
    report = { issues: { numErrors: 1, numWarnings: 0, numInfos: 0, numHints: 0,
                         messages: [{ code: 'UNPARSEABLE', severity: 0, message: String(e) }] } };
  }
  const is = report.issues;
  const issues = is.messages
    .filter((m) => m.severity <= (infos ? 2 : 1))
    .slice(0, 20)
    .map((m) => ({ code: m.code, severity: SEVERITY[m.severity], pointer: m.pointer,
                   message: m.message }));
  console.log(JSON.stringify({ file, numErrors: is.numErrors, numWarnings: is.numWarnings,
                               numInfos: is.numInfos, numHints: is.numHints, issues }));
  if (is.numErrors > 0 || (strict && is.numWarnings > 0))
    failed = true;
}
process.exit(unreadable ? 2 : failed ? 1 : 0);
