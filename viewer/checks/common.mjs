// What the browser checks share: command-line options, starting `motion-lod view`, Chromium with
// software GL, and the ok/FAIL tally.
import { spawn } from 'node:child_process';
import { existsSync } from 'node:fs';

/// `--name value` pairs of the command line.
export function options(argv = process.argv.slice(2)) {
  return Object.fromEntries(
    argv.reduce((acc, a, i, all) => (a.startsWith('--') ? [...acc, [a.slice(2), all[i + 1]]] : acc), []),
  );
}

/// Debian's Chromium ($CHROMIUM, /usr/bin/chromium or /usr/bin/chromium-browser).
export function chromiumPath() {
  const path = process.env.CHROMIUM ?? ['/usr/bin/chromium', '/usr/bin/chromium-browser'].find(existsSync);
  if (!path) throw new Error('no Chromium found (install Debian package `chromium` or set $CHROMIUM)');
  return path;
}

/// Chromium's flags for WebGL on the CPU (SwiftShader) in a container.
export const CHROMIUM_ARGS = ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'];

/// Starts `BIN view [FILE] --port 0` and resolves to `{ url, child, line }` once it prints its
/// address (20 s at most).
export function serve(bin, file) {
  return new Promise((resolve, reject) => {
    const child = spawn(bin, ['view', ...(file ? [file] : []), '--port', '0'], { stdio: ['ignore', 'pipe', 'inherit'] });
    let out = '';
    const timer = setTimeout(() => reject(new Error(`motion-lod view printed no address: ${out}`)), 20000);
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/http:\/\/[^\s]+\//);
      if (m) {
        clearTimeout(timer);
        resolve({ url: m[0], child, line: out.trim() });
      }
    });
    child.on('exit', (code) => reject(new Error(`motion-lod view exited with ${code}: ${out}`)));
  });
}

/// The ok/FAIL tally: `check(ok, what)` prints a line; `done()` prints the totals and exits 1 on
/// any failure.
export function tally() {
  let passed = 0;
  let failed = 0;
  return {
    check(ok, what) {
      console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
      if (ok) passed++;
      else failed++;
    },
    done() {
      console.log(`${passed} passed, ${failed} failed`);
      process.exit(failed > 0 ? 1 : 0);
    },
  };
}
