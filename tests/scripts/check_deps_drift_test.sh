#!/usr/bin/env bash
# scripts/check-deps.sh must fail when docs/architecture.md's table and the
# includes disagree: the document as it is passes, a copy whose fit row lacks
# `geometry` (which fit includes) fails naming fit and geometry, a copy whose
# eval row adds `sim` (which eval does not include) fails naming eval and sim,
# and a row naming a dependency the script does not know fails naming it.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
script="$root/scripts/check-deps.sh"
doc="$root/docs/architecture.md"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
failures=0

# expect NAME EXIT_CODE PATTERN... : runs the script on $tmp/NAME.md.
expect() {
  local name="$1" want="$2" out code pattern
  shift 2
  out="$("$script" --doc "$tmp/$name.md" 2>&1)"
  code=$?
  if [[ $code -ne $want ]]; then
    echo "FAIL $name: exit $code, expected $want; output:"
    echo "$out"
    failures=$((failures + 1))
    return
  fi
  for pattern in "$@"; do
    if ! grep -q -- "$pattern" <<<"$out"; then
      echo "FAIL $name: output lacks '$pattern'; output:"
      echo "$out"
      failures=$((failures + 1))
    fi
  done
}

# change NAME ROW_PREFIX SED_EXPRESSION: a copy with one row changed, which
# must differ from the document (else the test would test nothing).
change() {
  local name="$1" prefix="$2" expr="$3"
  sed "/^| \`${prefix//\//\\/}\`/ $expr" "$doc" >"$tmp/$name.md"
  if cmp -s "$doc" "$tmp/$name.md"; then
    echo "FAIL $name: the edit '$expr' of the row '$prefix' changed nothing"
    failures=$((failures + 1))
  fi
}

cp "$doc" "$tmp/unchanged.md"
expect unchanged 0
change missing 'libcalib/fit/' 's/, geometry,/,/'
expect missing 1 'libcalib/fit/: includes geometry but its row'
change extra 'libcalib/eval/' 's/| model |$/| model, sim |/'
expect extra 1 'libcalib/eval/: its row in .* lists sim'
change unknown 'libcalib/eval/' 's/| model |$/| model, Boost |/'
expect unknown 1 "names 'Boost', which is neither a folder nor a known external library"

if [[ $failures -ne 0 ]]; then
  exit 1
fi
echo "check-deps.sh fails on a table with a missing, an extra and an unknown dependency"
