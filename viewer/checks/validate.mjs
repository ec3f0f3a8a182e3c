// Runs the Khronos glTF validator over .glb files and fails on any error or warning.
//
//   node checks/validate.mjs FILE_OR_DIR... [--expect NAME,NAME...]
//
// A folder stands for every .glb in it. `--expect` names files that must be among those checked
// (CI: a walk and a crowd clip from the embedded data and from each shared data set).
import { readFileSync, readdirSync, statSync } from 'node:fs';
import { basename, join } from 'node:path';
import validator from 'gltf-validator';

const args = process.argv.slice(2);
const files = [];
let expected = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--expect') {
    expected = args[++i].split(',').filter(Boolean);
  } else if (statSync(args[i]).isDirectory()) {
    for (const f of readdirSync(args[i]).sort()) {
      if (f.endsWith('.glb')) files.push(join(args[i], f));
    }
  } else {
    files.push(args[i]);
  }
}
const names = new Set(files.map((f) => basename(f)));
const missing = expected.filter((e) => !names.has(e));
if (missing.length > 0) {
  console.error(`missing exports: ${missing.join(', ')}`);
  process.exit(1);
}
if (files.length === 0) {
  console.error('no .glb file to validate');
  process.exit(1);
}
let failed = 0;
for (const file of files) {
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
    uri: basename(file),
    maxIssues: 50,
  });
  const { numErrors, numWarnings, numInfos, numHints } = report.issues;
  console.log(
    `${file}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos, ${numHints} hints` +
      ` (${report.info.animationCount} animation, ${report.info.totalVertexCount} vertices)`,
  );
  for (const m of report.issues.messages) {
    if (m.severity <= 1) console.log(`  ${['error', 'warning'][m.severity]} ${m.code} ${m.pointer ?? ''}: ${m.message}`);
  }
  if (numErrors > 0 || numWarnings > 0) failed++;
}
console.log(`${files.length - failed} passed, ${failed} failed`);
process.exit(failed > 0 ? 1 : 0);
