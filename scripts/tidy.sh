#!/usr/bin/env bash
# Runs clang-tidy (.clang-tidy's checks, warnings are errors) on every C++ source of the tree.
# Needs a configured build folder with compile_commands.json.
# Usage: scripts/tidy.sh [BUILD_DIR (default build)] [JOBS (default 2)]
set -uo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
jobs=${2:-2}
if [[ ! -f "$build/compile_commands.json" ]]; then
  echo "tidy.sh: $build/compile_commands.json not found; configure first: cmake -S . -B $build" >&2
  exit 2
fi
if ! command -v clang-tidy >/dev/null; then
  echo "tidy.sh: clang-tidy is not installed (apt-get install clang-tidy)" >&2
  exit 2
fi
log=$(mktemp)
git ls-files '*.cc' | xargs -P "$jobs" -n 4 clang-tidy -p "$build" --quiet >"$log" 2>&1
status=$?
grep -v -E '^[0-9]+ warnings? (and [0-9]+ errors? )?generated|^Suppressed [0-9]+ warnings|^Use -header-filter' "$log"
rm -f "$log"
if ((status != 0)); then
  echo "tidy.sh: clang-tidy found problems (above)" >&2
  exit 1
fi
echo "tidy.sh: clean"
