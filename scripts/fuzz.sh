#!/usr/bin/env bash
# Runs the libFuzzer harnesses of fuzz/ (built into build-fuzz by `make fuzz`),
# FUZZ_JOBS of them at a time (default: the number of cores; each harness is
# one in-process libFuzzer run on one core, so a fixed-seed run is the same
# run whatever the other harnesses do), seeded
# from tests/data (good and malformed files, by extension) and the seeds
# make_seeds writes; the corpus grows in build-fuzz/corpus/<harness>.
# Usage: scripts/fuzz.sh [--seconds N | --runs N] [harness ...]
#   --seconds N  run each harness N seconds (default 15: what CI runs)
#   --runs N     run each harness N executions (docs/reliability.md: 10^7)
# Prints one line per harness ("fuzz <name>: <runs> runs in <s> s, ok") and
# exits non-zero if any harness found a crash, leak, timeout or sanitizer
# report (its log's tail is printed; the input is left in build-fuzz/artifacts/).
set -euo pipefail
cd "$(dirname "$0")/.."
B=${FUZZ_BUILD:-build-fuzz}
limit=(-max_total_time=15)
harnesses=()
while (($#)); do
  case "$1" in
    --seconds) limit=(-max_total_time="$2"); shift 2 ;;
    --runs) limit=(-runs="$2"); shift 2 ;;
    *) harnesses+=("$1"); shift ;;
  esac
done
if ((${#harnesses[@]} == 0)); then
  harnesses=(obj ply off atm atd template mhclo mh_target mh_base mh_modifiers)
  # Built only once their parsers are in the tree (fuzz/CMakeLists.txt).
  for h in curve_network strokes feature_curves; do [[ -x $B/${h}_fuzz ]] && harnesses+=("$h"); done
fi

# Seeds: tests/data by extension, then the generated ones.
seeds=$B/seeds
rm -rf "$seeds"
mkdir -p "$seeds" "$B/artifacts"
for f in tests/data/good/* tests/data/malformed/*; do
  ext=${f##*.}
  mkdir -p "$seeds/$ext"
  cp "$f" "$seeds/$ext/"
done
"$B/make_seeds" "$seeds"

# FUZZ_SEED: a fixed libFuzzer seed, so that a run of a fixed number of
# executions is the same run every time (CI: a red build is reproducible
# and never a matter of luck).
seed=()
[[ -n ${FUZZ_SEED:-} ]] && seed=(-seed="$FUZZ_SEED")
# FUZZ_MAX_LEN: the largest input libFuzzer makes (and the length corpus files
# are cut to when loaded). 64 KiB by default; a long run may lower it, since
# a parser's per-line states are all reached by short inputs and an obj
# corpus of 20 kB inputs runs at a third of the speed.
max_len=${FUZZ_MAX_LEN:-65536}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:symbolize=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# One harness: its log in $B/logs, its result line in $B/logs/<h>.result.
run_one() {
  local h=$1 corpus=$B/corpus/$1 seed_dir=$seeds/$1 log=$B/logs/$1.log start runs
  mkdir -p "$corpus"
  [[ -d $seed_dir ]] || mkdir -p "$seed_dir"
  start=$(date +%s)
  # -timeout: one input taking 10 s is a hang; -rss_limit_mb: a parser that
  # allocates what a header claims instead of what the bytes hold.
  if ! "$B/${h}_fuzz" "${limit[@]}" "${seed[@]}" -timeout=10 -rss_limit_mb=2048 -max_len="$max_len" -print_final_stats=1 \
       -artifact_prefix="$B/artifacts/${h}-" "$corpus" "$seed_dir" >"$log" 2>&1; then
    echo "fuzz $h: FAILED (see $log and $B/artifacts/)" >"$B/logs/$h.result"
    return 1
  fi
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  echo "fuzz $h: ${runs:-?} runs in $(( $(date +%s) - start )) s, ok (corpus $(ls "$corpus" | wc -l) files)" >"$B/logs/$h.result"
}
mkdir -p "$B/logs"
jobs_max=${FUZZ_JOBS:-$(nproc)}
rm -f "$B"/logs/*.result
for h in "${harnesses[@]}"; do
  while (( $(jobs -rp | wc -l) >= jobs_max )); do wait -n || true; done
  run_one "$h" &
done
wait || true
# The verdict from the result files (a job's status may already have been
# collected by `wait -n`).
failed=0
for h in "${harnesses[@]}"; do
  if grep -q ', ok ' "$B/logs/$h.result" 2>/dev/null; then
    cat "$B/logs/$h.result"
  else
    failed=1
    cat "$B/logs/$h.result" 2>/dev/null || echo "fuzz $h: FAILED (no result)"
    tail -40 "$B/logs/$h.log"
  fi
done
exit $failed
