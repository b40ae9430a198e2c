#!/usr/bin/env bash
# scripts/fuzz.sh [SECONDS] [HARNESS...]
#
# Runs the libFuzzer harnesses of fuzz/: `frontend` (lex, split names, parse and check one module),
# `ir` (lowering, every IR pass with the IR verified after each, evaluation, GLSL printing) and `scene`
# (the whole compiler on a scene, document or module file, through glslang; exit 3 counts as a crash).
# Each runs SECONDS (default 60) with one job on its corpus in build-asan/fuzz/corpus/HARNESS, seeded from
# examples/, stdlib/ and tests/ (every regression input in tests/fuzz/HARNESS/ included), with the token
# dictionary fuzz/iqc.dict, 120 s and 2 GB per input, and a fixed seed (IQC_FUZZ_SEED, default 1: CI fuzzes
# the same inputs on every run, so a red run is a reproducible one; set it to 0 for a random seed). The harnesses live in the sanitizer build
# (scripts/sanitize.sh; built here if missing), so every ASan/UBSan report is a finding too.
#
# A long campaign (the issue-16 report: `IQC_FUZZ_BUILD=build-fuzz IQC_FUZZ_SANITIZERS=undefined
# IQC_FUZZ_JOBS=2 IQC_FUZZ_TIMEOUT=120 nice -n 10 bash scripts/fuzz.sh 3600`) may use a build of its own with
# UBSan alone, several times the executions per second of ASan's; IQC_FUZZ_JOBS runs that many processes per
# harness; IQC_FUZZ_TIMEOUT is the seconds per input (default 120). The harnesses' build (ASan, UBSan and
# libFuzzer's coverage instrumentation) compiles about 40× slower than a release build: the seeds' Mandelbulb (0.8 s
# in release) takes 38 s there and the Christmas tree 21 s, on 2 cores; a 10 s limit reported them as hangs (the CI
# stopped at a 10 s one). 120 s is the sanitizer suite's own bound per compile (tests/hostile_test.cpp), and a hang
# still ends the run. The timeout is wall time: at nice 19 beside two busy processes (ctest -j2, a build) a fuzzer
# gets about 1% of a core, and an input of 4 s reached 60 s and was reported as a hang; nice 10 gets it about 5%.
#
# A finding stops that harness with the input in build-asan/fuzz/artifacts/. Minimise it with
#   build-asan/fuzz/fuzz_HARNESS -minimize_crash=1 -runs=100000 ARTIFACT
# fix the bug, and add the input under tests/fuzz/HARNESS/ (the property test in tests/hostile_test.cpp
# runs it from then on). Prints the executions of each harness; exit status 1 when any found something.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_EACH="${1:-60}"
shift || true
HARNESSES=("$@")
[ ${#HARNESSES[@]} -eq 0 ] && HARNESSES=(frontend ir scene)

B="${IQC_FUZZ_BUILD:-build-asan}"
JOBS="${IQC_FUZZ_JOBS:-1}"
if [ ! -f "$B/CMakeCache.txt" ]; then
  bash scripts/install-deps.sh
  CC=clang CXX=clang++ cmake -S . -B "$B" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIQC_SANITIZE=ON \
    -DIQC_SANITIZERS="${IQC_FUZZ_SANITIZERS:-address,undefined}" >/dev/null
fi
targets=()
for h in "${HARNESSES[@]}"; do targets+=("fuzz_$h"); done
cmake --build "$B" -j "$(nproc)" --target "${targets[@]}"
source scripts/sanitizer-env.sh
# Fuzzing trades the costly stack-use-after-return check for executions (the test suite keeps it).
export ASAN_OPTIONS="$ASAN_OPTIONS:detect_stack_use_after_return=0"

# Seeds: the modules and scenes the project ships and tests, one file per distinct content.
seed() {  # seed DIR FILE...
  local dir="$1"; shift
  for f in "$@"; do
    [ -f "$f" ] || continue
    cp "$f" "$dir/$(sha1sum "$f" | cut -c1-40)"
  done
}
seed_modules() {  # the module texts of documents and conformance tests, one file each
  local dir="$1"
  python3 - "$dir" examples/*.md tests/conformance/*.iqtest <<'PY'
import hashlib, os, re, sys
out = sys.argv[1]
for path in sys.argv[2:]:
    text = open(path, encoding="utf-8").read()
    blocks = re.findall(r"```iheartla\n(.*?)```", text, re.S)
    blocks += re.findall(r"^--- module\n(.*?)(?=^---|^###|\Z)", text, re.S | re.M)
    for b in blocks:
        name = hashlib.sha1(b.encode()).hexdigest()
        with open(os.path.join(out, name), "w", encoding="utf-8") as f:
            f.write(b)
PY
}
for h in "${HARNESSES[@]}"; do
  corpus="$B/fuzz/corpus/$h"
  mkdir -p "$corpus" "$B/fuzz/artifacts"
  if [ "$h" = scene ]; then
    seed "$corpus" examples/* tests/hardcases/*.iq tests/hostile/*.iq tests/hostile/*.iql stdlib/*.iql golden/*/*.md
  else
    seed "$corpus" stdlib/*.iql tests/hostile/*.iql
    seed_modules "$corpus"
  fi
  seed "$corpus" tests/fuzz/"$h"/*
done

status=0
total=0
for h in "${HARNESSES[@]}"; do
  log="$B/fuzz/$h.log"
  stamp="$B/fuzz/$h.started"
  touch "$stamp"
  set +e
  max_len=8192
  [ "$h" = scene ] && max_len=32768
  # JOBS processes (default one: the machine is shared), each logging to $log.N, sharing the corpus; the
  # seed of process N is the seed plus N.
  rc=0
  pids=()
  for ((j = 0; j < JOBS; j++)); do
    seed_j=$(( ${IQC_FUZZ_SEED:-1} == 0 ? 0 : ${IQC_FUZZ_SEED:-1} + j ))
    "$B/fuzz/fuzz_$h" "$B/fuzz/corpus/$h" -dict=fuzz/iqc.dict \
      -seed="$seed_j" -max_total_time="$SECONDS_EACH" -timeout="${IQC_FUZZ_TIMEOUT:-120}" -rss_limit_mb=2048 -max_len="$max_len" -print_final_stats=1 \
      -artifact_prefix="$B/fuzz/artifacts/$h-" >"$log.$j" 2>&1 &
    pids+=($!)
  done
  for p in "${pids[@]}"; do wait "$p" || rc=$?; done
  set -e
  cat "$log".* > "$log"
  runs=0
  for ((j = 0; j < JOBS; j++)); do
    r=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log.$j" | grep -o '[0-9]*$' | tail -1)
    runs=$((runs + ${r:-0}))
  done
  total=$((total + runs))
  if [ $rc -ne 0 ]; then
    status=1
    echo "fuzz $h: FOUND A PROBLEM after $runs executions (exit $rc); see $log and $B/fuzz/artifacts/"
    # What the harness printed before it stopped (diagnostics, sanitizer report) and the input, in base64.
    grep -v -E '^#[0-9]+|^INFO:|^\s*$' "$log" | tail -40 || true
    for a in $(find "$B/fuzz/artifacts" -name "$h-*" -newer "$stamp"); do
      echo "input $a (base64):"
      head -c 4096 "$a" | base64 -w 100
    done
  else
    echo "fuzz $h: $runs executions in ${SECONDS_EACH} s, nothing found"
  fi
done
echo "fuzz: $total executions in all"
exit $status
