#!/usr/bin/env bash
# Runs the same jobs with two builds of atelier and compares every output
# file byte for byte (issue 19: a restructuring must not change results).
#
# Usage: scripts/compare_outputs.sh OLD NEW [WORK]
#   OLD, NEW: a git revision (built here in a worktree under WORK) or the
#             path of an already built `atelier` binary.
#   WORK:     scratch folder (default /tmp/atelier-compare).
# Environment: BODIES (default 60), DATA (default ../shared/data; the
#   MakeHuman job runs only when it exists).
#
# Jobs, each with --seed 7 on 2 threads:
#   demo --bodies $BODIES;
#   encode --template all, encode --garment (the demo's shorts);
#   regen of the three profile templates and the shorts' detail template on
#   $BODIES mannequins, with meshes for the first 5;
#   with the shared data: encode and regen of a MakeHuman garment on 20 adults.
# Timings are not results: report.json's and report.html's timing fields and
# timing.json are dropped before comparing, and so are the demo pictures
# chosen by a timing ("highest top_ms"); pictures are compared by pixels. Exit 0 when every other file is
# identical; else the differing files are listed and the exit code is 1.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
old=${1:?usage: compare_outputs.sh OLD NEW [WORK]}
new=${2:?usage: compare_outputs.sh OLD NEW [WORK]}
work=${3:-/tmp/atelier-compare}
bodies=${BODIES:-60}
data=${DATA:-$here/../shared/data}
mkdir -p "$work"

# The atelier binary of a revision (built once per revision) or a given path.
binary_of() {
  local rev=$1
  if [[ -x $rev && ! -d $rev ]]; then
    echo "$rev"
    return
  fi
  local sha
  sha=$(git -C "$here" rev-parse --short "$rev")
  local tree=$work/tree-$sha
  if [[ ! -x $tree/build/atelier ]]; then
    [[ -d $tree ]] || git -C "$here" worktree add --detach "$tree" "$sha" >&2
    cmake -S "$tree" -B "$tree/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DATELIER_BUILD_TESTS=OFF \
      -DATELIER_BUILD_BENCH=OFF >&2
    cmake --build "$tree/build" --target atelier -j "$(nproc)" >&2
  fi
  echo "$tree/build/atelier"
}

run_jobs() {
  local bin=$1 out=$2
  rm -rf "$out"
  mkdir -p "$out"
  local g=(--seed 7 --threads 2 --quiet)
  "$bin" "${g[@]}" demo --bodies "$bodies" --out "$out/demo" >"$out/demo.txt"
  "$bin" "${g[@]}" encode --template all --reference mannequin --out "$out/templates" >"$out/encode.txt"
  "$bin" "${g[@]}" encode --garment "$out/demo/garment_template.obj" --reference mannequin \
    --out "$out/templates" >>"$out/encode.txt"
  "$bin" "${g[@]}" regen --template "$out/templates/top.template.json" \
    --template "$out/templates/skirt.template.json" --template "$out/templates/trousers.template.json" \
    --template "$out/templates/garment_template.atd" --source mannequin --count "$bodies" --meshes 5 \
    --out "$out/regen" >"$out/regen.txt"
  if [[ -d $data/makehuman ]]; then
    local clo=$data/makehuman/clothes/male_casualsuit01.mhclo
    "$bin" "${g[@]}" encode --garment "$clo" --reference makehuman --data "$data" \
      --out "$out/mh_templates" >"$out/mh_encode.txt"
    "$bin" "${g[@]}" regen --template "$out/mh_templates/male_casualsuit01.atd" --source makehuman \
      --data "$data" --count 20 --meshes 3 --out "$out/mh_regen" >"$out/mh_regen.txt"
  fi
}

# Drops what is a timing, not a result.
normalise() {
  local out=$1
  rm -f "$out"/*/timing.json "$out"/*.txt
  python3 - "$out" <<'EOF'
import json, os, re, sys
root = sys.argv[1]
timing = re.compile(r'(^|_)(ms|s|ms_per_body|per_s)$|^(total_s|encode_s|bodies_per_s|decode_ms)$')
def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items() if not timing.search(k)}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x
for dirpath, _, files in os.walk(root):
    for f in files:
        p = os.path.join(dirpath, f)
        if f.endswith('.json') and 'bodies' not in dirpath.split(os.sep)[-1:]:
            try:
                d = json.load(open(p))
            except Exception:
                continue
            json.dump(strip(d), open(p, 'w'), indent=1, sort_keys=True)
        elif f == 'report.html':
            html = open(p, encoding='utf-8').read()
            for m in re.finditer(r'<figcaption><b>([^<(]+) \(highest top_ms\)</b>', html):
                pic = os.path.join(dirpath, 'pictures', m.group(1).strip() + '.png')
                if os.path.exists(pic):
                    os.remove(pic)
            os.remove(p)  # its tables and pictures come from report.json and pictures/
# Pictures are compared by their pixels: the PNG encoder (libpng since
# issue 19) decides the compressed bytes.
import struct, zlib
def png_pixels(path):
    b = open(path, 'rb').read()
    pos, idat, w, h = 8, b'', 0, 0
    while pos < len(b):
        n, t = struct.unpack('>I4s', b[pos:pos + 8])
        data = b[pos + 8:pos + 8 + n]
        if t == b'IHDR':
            w, h, depth, colour = struct.unpack('>IIBB', data[:10])
            assert depth == 8 and colour == 2 and data[12] == 0, path
        elif t == b'IDAT':
            idat += data
        pos += 12 + n
    raw, out, prev, stride = zlib.decompress(idat), bytearray(), bytearray(3 * w), 3 * w
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 3] if i >= 3 else 0
            c = prev[i - 3] if i >= 3 else 0
            pb = prev[i]
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + pb) & 255
            elif f == 3: line[i] = (line[i] + (a + pb) // 2) & 255
            elif f == 4:
                pa, pp, pc = abs(pb - c), abs(a - c), abs(a + pb - 2 * c)
                line[i] = (line[i] + (a if pa <= pp and pa <= pc else pb if pp <= pc else c)) & 255
        out += line
        prev = line
    return b'%d %d\n' % (w, h) + bytes(out)
# Detail templates are compared by their content: version 2 of the .atd
# format (issue 19) ends in a CRC-32 where version 1 had an FNV-1a sum.
for dirpath, _, files in os.walk(root):
    for f in files:
        if f.endswith('.atd'):
            p = os.path.join(dirpath, f)
            b = open(p, 'rb').read()
            version = struct.unpack('<I', b[8:12])[0]
            open(p + '.content', 'wb').write(b[:8] + b[12:len(b) - (8 if version == 1 else 4)])
            os.remove(p)
for dirpath, _, files in os.walk(root):
    for f in files:
        if f.endswith('.png'):
            p = os.path.join(dirpath, f)
            open(p + '.pixels', 'wb').write(png_pixels(p))
            os.remove(p)
EOF
  # Pictures are removed with report.html above; the one chosen by a timing
  # ("(highest top_ms)" in its title) is dropped, the others compared.
  :
}

old_bin=$(binary_of "$old")
new_bin=$(binary_of "$new")
echo "old: $old_bin"
echo "new: $new_bin"
run_jobs "$old_bin" "$work/out-old"
run_jobs "$new_bin" "$work/out-new"
normalise "$work/out-old"
normalise "$work/out-new"
files=$(cd "$work/out-old" && find . -type f | sort)
count=$(echo "$files" | wc -l)
if diff -rq "$work/out-old" "$work/out-new" >"$work/diff.txt"; then
  echo "identical: $count files (demo, encode, regen$([[ -d $data/makehuman ]] && echo ', MakeHuman regen'))"
  exit 0
fi
echo "DIFFERENT ($(wc -l <"$work/diff.txt") of $count files); by how much:"
# For differing OBJ files the largest vertex coordinate difference, for JSON
# files the largest difference of a number (same keys required), per folder.
python3 - "$work/out-old" "$work/out-new" <<'EOF2'
import json, os, sys
old, new = sys.argv[1], sys.argv[2]
def verts(p):
    return [tuple(map(float, l.split()[1:4])) for l in open(p) if l.startswith('v ')]
def nums(x, out, path=''):
    if isinstance(x, dict):
        for k in sorted(x): nums(x[k], out, path + '/' + k)
    elif isinstance(x, list):
        for i, v in enumerate(x): nums(v, out, path + '[%d]' % i)
    else: out[path] = x
summary = {}
for dirpath, _, files in os.walk(old):
    for f in files:
        a = os.path.join(dirpath, f); b = a.replace(old, new, 1)
        if not os.path.exists(b) or open(a, 'rb').read() == open(b, 'rb').read(): continue
        group = os.path.relpath(dirpath, old).split(os.sep)[0] + '/*' + os.path.splitext(f)[1]
        d = float('nan')
        if f.endswith('.obj'):
            va, vb = verts(a), verts(b)
            if len(va) == len(vb): d = max(max(abs(x - y) for x, y in zip(p, q)) for p, q in zip(va, vb))
        elif f.endswith('.json'):
            na, nb = {}, {}
            nums(json.load(open(a)), na); nums(json.load(open(b)), nb)
            if na.keys() == nb.keys():
                d = max([abs(na[k] - nb[k]) for k in na if isinstance(na[k], (int, float)) and not isinstance(na[k], bool)] + [0])
                if any(na[k] != nb[k] for k in na if not isinstance(na[k], (int, float)) or isinstance(na[k], bool)): d = float('nan')
        n, m = summary.get(group, (0, 0.0))
        summary[group] = (n + 1, m if d != d or m != m else max(m, d)) if d == d else (n + 1, float('nan'))
for g, (n, m) in sorted(summary.items()):
    print('  %-28s %4d files differ, largest difference %s' % (g, n, 'structural' if m != m else '%.3g' % m))
EOF2
exit 1
