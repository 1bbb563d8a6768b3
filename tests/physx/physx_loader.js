'use strict';
// Loads the PhysX 5.6.1 WebAssembly build (npm package physx-js-webidl) under node.
//
// The package is built for web pages only: its start-up code refuses to run when it
// sees node's global `process`, and picks its browser code path only when a global
// `window` exists. So while the module initialises we hide `process`, provide an empty
// `window`, and hand it the .wasm file's bytes directly (no fetch()). Both globals are
// restored as soon as initialisation has finished.

const fs = require('fs');
const path = require('path');
const url = require('url');

function findPackageDir(startDir) {
  const candidates = [];
  if (process.env.FEATHERDRIVE_PHYSX_MODULES) {
    candidates.push(path.join(process.env.FEATHERDRIVE_PHYSX_MODULES, 'physx-js-webidl'));
  }
  candidates.push(path.join(startDir, 'node_modules', 'physx-js-webidl'));
  for (const dir of candidates) {
    if (fs.existsSync(path.join(dir, 'physx-js-webidl.mjs')) &&
        fs.existsSync(path.join(dir, 'physx-js-webidl.wasm'))) {
      return dir;
    }
  }
  throw new Error('physx-js-webidl is not installed (looked in: ' + candidates.join(', ') +
                  '); run install.sh first');
}

async function loadPhysX(startDir) {
  const dir = findPackageDir(startDir || __dirname);
  const factory = (await import(url.pathToFileURL(path.join(dir, 'physx-js-webidl.mjs')).href)).default;
  const wasmBinary = fs.readFileSync(path.join(dir, 'physx-js-webidl.wasm'));

  const processDesc = Object.getOwnPropertyDescriptor(globalThis, 'process');
  const hadWindow = Object.prototype.hasOwnProperty.call(globalThis, 'window');
  const oldWindow = globalThis.window;
  let P;
  try {
    delete globalThis.process;
    globalThis.window = {};
    P = await factory({ wasmBinary });
  } finally {
    if (processDesc) Object.defineProperty(globalThis, 'process', processDesc);
    if (hadWindow) globalThis.window = oldWindow; else delete globalThis.window;
  }
  return P;
}

module.exports = { loadPhysX };
