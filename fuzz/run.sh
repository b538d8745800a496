#!/usr/bin/env bash
# Builds the reader fuzzers (clang, libFuzzer, ASan, UBSan) in build-fuzz/ and
# runs each for SECONDS_EACH seconds (default 30). See docs/fuzzing.md.
#
#   fuzz/run.sh [SECONDS_EACH] [FUZZER...]     e.g. fuzz/run.sh 600 records model
#
# New corpus entries go to build-fuzz/fuzz-work/corpus/<fuzzer>/ (never into
# the repository); crashing inputs to build-fuzz/fuzz-work/crashes/<fuzzer>/.
# Exits non-zero if any fuzzer found a crash. Environment: BUILD_DIR (default
# build-fuzz), NICE (niceness, default 5).
set -euo pipefail

seconds=${1:-30}
shift || true
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build-fuzz}
nice_level=${NICE:-5}
fuzzers=("$@")
if [ ${#fuzzers[@]} -eq 0 ]; then
  for source in "$root"/fuzz/*_fuzzer.cc; do
    name=$(basename "$source" _fuzzer.cc)
    fuzzers+=("$name")
  done
fi

launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
mkdir -p "$build"
CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DRTSCALIB_FUZZ=ON -DRTSCALIB_WITH_RENDER=OFF -DRTSCALIB_BUILD_TESTS=OFF \
  -DRTSCALIB_BUILD_BENCHMARKS=OFF "${launcher[@]}" > "$build/configure.log" 2>&1 ||
  { cat "$build/configure.log"; exit 1; }
targets=()
for f in "${fuzzers[@]}"; do targets+=("${f}_fuzzer"); done
nice -n "$nice_level" cmake --build "$build" -j2 --target "${targets[@]}"

# The dictionary of a fuzzer: dict/<name>.dict, else the one of its seeds'
# format (dict/csv.dict for .csv seeds, dict/yaml.dict for .yaml).
dict_of() {
  if [ -f "$root/fuzz/dict/$1.dict" ]; then
    echo "$root/fuzz/dict/$1.dict"
    return
  fi
  local seed
  seed=$(find "$root/fuzz/corpus/$1" -type f -name '*.*' | head -1)
  echo "$root/fuzz/dict/${seed##*.}.dict"
}

work=$build/fuzz-work
failed=()
for f in "${fuzzers[@]}"; do
  corpus=$work/corpus/$f
  crashes=$work/crashes/$f
  mkdir -p "$corpus" "$crashes"
  log=$work/$f.log
  echo "== $f: ${seconds}s (log $log)"
  # The first corpus folder receives new entries; the committed one is only read.
  if nice -n "$nice_level" "$build/fuzz/${f}_fuzzer" -max_total_time="$seconds" -rss_limit_mb=2048 \
    -timeout=30 -print_final_stats=1 -dict="$(dict_of "$f")" \
    -artifact_prefix="$crashes/" "$corpus" "$root/fuzz/corpus/$f" > "$log" 2>&1; then
    grep -E '^#[0-9]+[[:space:]]+DONE|stat::number_of_executed_units' "$log" | tail -2
  else
    echo "!! $f found a crash:"
    grep -E 'rtscalib fuzz|ERROR|SUMMARY|Test unit written' "$log" | head -8
    failed+=("$f")
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "crashes in: ${failed[*]} (inputs in $work/crashes/)"
  exit 1
fi
echo "no crashes"
