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
# chosen by a timing ("highest top_ms"). Exit 0 when every other file is
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
echo "DIFFERENT ($(wc -l <"$work/diff.txt") of $count files):"
cat "$work/diff.txt"
exit 1
