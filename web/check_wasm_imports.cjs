// Fails the build when the WebAssembly decoder imports a C++ function: a meshflow source file the
// decoder needs is missing from web/CMakeLists.txt's decoder_sources. The decoder links with
// ERROR_ON_UNDEFINED_SYMBOLS=0 (the encoder's calls into the decimation are left out), so
// emscripten turns such a function into an import that aborts the page when it is called (a
// colour decoder's vertex_adjacency() once did, found only by the browser test). Imports of
// emscripten's runtime (emscripten_*, abort, fd_write, ...) are C names and pass.
//
// usage: node check_wasm_imports.cjs DECODER.wasm   (exit 1 naming each C++ import; the .wasm is
// then deleted, so the next build makes it again instead of taking it for up to date)
'use strict';
const fs = require('fs');
const path = process.argv[2];
const decoder = new WebAssembly.Module(fs.readFileSync(path));
const missing = WebAssembly.Module.imports(decoder)
  .filter((i) => i.kind === 'function' && i.name.startsWith('_Z'))
  .map((i) => `${i.module}.${i.name}`);
if (missing.length > 0) {
  console.error(`${path}: the decoder imports ${missing.length} C++ function(s) nobody defines ` +
                '(add their source files to decoder_sources in web/CMakeLists.txt):');
  for (const name of missing) console.error(`  ${name}`);
  fs.unlinkSync(path);
  process.exit(1);
}
