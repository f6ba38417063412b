// Peer for bench/net/net_bench.cpp: times manifold-3d's Booleans on two OBJ
// files, in-process (node start-up and file parsing excluded).
//   node manifold_bool.mjs A.obj B.obj union|intersection|difference REPS
// Prints one JSON line: {"ms":[...], "ms_build":[...], "volume":V, "triangles":T, "status":S}
// (ms: the Boolean of two ready Manifolds; ms_build: the two Manifolds made
// from the parsed meshes plus the Boolean)
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
  const meshA = readObj(a), meshB = readObj(b);
  const make = (m) => new Manifold(new Mesh({ numProp: 3, ...m }));
  const A = make(meshA), B = make(meshB);
  const ms = [];
  // The same Boolean with both Manifolds made from the parsed meshes inside
  // the timing (what net_boolean does with its polygon soups every call).
  const msBuild = [];
  for (let r = 0; r < reps; ++r) {
    const t0 = performance.now();
    const A2 = make(meshA), B2 = make(meshB);
    const out = op === 'union' ? A2.add(B2) : op === 'intersection' ? A2.intersect(B2) : A2.subtract(B2);
    out.numTri();
    msBuild.push(performance.now() - t0);
    out.delete();
    A2.delete();
    B2.delete();
  }
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
  console.log(JSON.stringify({ ms, ms_build: msBuild, volume, triangles, status, status_a: String(A.status()), status_b: String(B.status()) }));
} catch (e) {
  console.log(JSON.stringify({ error: String(e) }));
}
