// Peer for bench/net/net_bench.cpp: times manifold-3d's Booleans on two OBJ
// files, in-process (node start-up and file parsing excluded).
//   node manifold_bool.mjs A.obj B.obj union|intersection|difference REPS
// Prints one JSON line: {"ms":[...], "volume":V, "triangles":T, "status":S}
// or {"error":"..."} (exit 0 either way: the benchmark reports it).
import Module from 'manifold-3d';
import { readFileSync } from 'node:fs';

function readObj(path) {
  const v = [], t = [];
  for (const line of readFileSync(path, 'utf8').split('\n')) {
    const w = line.trim().split(/\s+/);
    if (w[0] === 'v') v.push(+w[1], +w[2], +w[3]);
    else if (w[0] === 'f') {
      const idx = w.slice(1).map((s) => parseInt(s.split('/')[0], 10) - 1);
      for (let k = 1; k + 1 < idx.length; ++k) t.push(idx[0], idx[k], idx[k + 1]);
    }
  }
  return { vertProperties: Float32Array.from(v), triVerts: Uint32Array.from(t) };
}

const [a, b, op, repsText] = process.argv.slice(2);
const reps = Math.max(1, parseInt(repsText ?? '1', 10));
try {
  const wasm = await Module();
  wasm.setup();
  const { Manifold, Mesh } = wasm;
  const make = (p) => new Manifold(new Mesh({ numProp: 3, ...readObj(p) }));
  const A = make(a), B = make(b);
  const ms = [];
  let volume = 0, triangles = 0, status = 'NoError';
  for (let r = 0; r < reps; ++r) {
    const t0 = performance.now();
    const out = op === 'union' ? A.add(B) : op === 'intersection' ? A.intersect(B) : A.subtract(B);
    triangles = out.numTri();  // forces the lazy CSG tree
    ms.push(performance.now() - t0);
    volume = out.volume();
    status = String(out.status());
    out.delete();
  }
  console.log(JSON.stringify({ ms, volume, triangles, status, status_a: String(A.status()), status_b: String(B.status()) }));
} catch (e) {
  console.log(JSON.stringify({ error: String(e) }));
}
