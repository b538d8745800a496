#!/usr/bin/env bash
# Checks that libcalib/CMakeLists.txt declares exactly the dependencies the
# code has: for every folder libcalib/<f>/, the libcalib folders and external
# libraries its headers and sources #include (found with grep) must equal the
# DEPS of its `rtscalib_add_layer(<f> DEPS ...)` line. A dependency declared
# but never included, or included but not declared, fails (exit 1) with one
# line per difference. Then the include graph of every folder of the tree
# (libcalib/<f>/, detect/, render/, app/) must have no circle: a folder that
# includes another, directly or through others, that includes it back fails,
# with the circle named (tsort). Run from anywhere; ctest runs it as
# `check_deps`.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cmake_file="$root/libcalib/CMakeLists.txt"

# External headers -> the CMake names libcalib/CMakeLists.txt uses for them.
external_deps() {
  local dir="$1"
  local includes
  includes="$(grep -ho '^#include <[^>]*>' "$dir"/*.h "$dir"/*.cc 2>/dev/null || true)"
  grep -q '<Eigen/' <<<"$includes" && echo 'Eigen3::Eigen'
  grep -q '<ceres/' <<<"$includes" && echo 'Ceres::ceres'
  grep -q '<opencv2/' <<<"$includes" && echo '${OpenCV_LIBS}'
  grep -q '<yaml-cpp/' <<<"$includes" && echo 'yaml-cpp'
  grep -q '<nlohmann/' <<<"$includes" && echo 'nlohmann_json::nlohmann_json'
  return 0
}

# libcalib folders included by this folder's files, as rtscalib_<folder>.
internal_deps() {
  local dir="$1" self="$2"
  grep -ho '^#include "libcalib/[a-z_0-9]*/' "$dir"/*.h "$dir"/*.cc 2>/dev/null |
    sed 's|^#include "libcalib/||; s|/$||' | grep -vx "$self" | sed 's/^/rtscalib_/' || true
}

status=0
declared_folders="$(sed -n 's/^rtscalib_add_layer(\([a-z_0-9]*\).*/\1/p' "$cmake_file" | sort)"
actual_folders="$(find "$root/libcalib" -mindepth 1 -maxdepth 1 -type d -printf '%f\n' | sort)"
while read -r f; do
  [[ -z "$f" ]] && continue
  echo "libcalib/$f/ has no rtscalib_add_layer($f ...) line in libcalib/CMakeLists.txt"
  status=1
done < <(comm -13 <(echo "$declared_folders") <(echo "$actual_folders"))
while read -r f; do
  [[ -z "$f" ]] && continue
  echo "libcalib/CMakeLists.txt declares layer '$f' but libcalib/$f/ does not exist"
  status=1
done < <(comm -23 <(echo "$declared_folders") <(echo "$actual_folders"))

for f in $(comm -12 <(echo "$declared_folders") <(echo "$actual_folders")); do
  dir="$root/libcalib/$f"
  actual="$({ internal_deps "$dir" "$f"; external_deps "$dir"; } | sort -u)"
  declared="$(sed -n "s/^rtscalib_add_layer($f[[:space:]]\+DEPS[[:space:]]*\(.*\))[[:space:]]*$/\1/p" \
    "$cmake_file" | tr -s ' \t' '\n' | grep -v '^$' | sort -u || true)"
  while read -r d; do
    [[ -z "$d" ]] && continue
    echo "libcalib/$f: includes $d but libcalib/CMakeLists.txt does not declare it"
    status=1
  done < <(comm -13 <(echo "$declared") <(echo "$actual"))
  while read -r d; do
    [[ -z "$d" ]] && continue
    echo "libcalib/$f: declares $d in libcalib/CMakeLists.txt but no file includes it"
    status=1
  done < <(comm -23 <(echo "$declared") <(echo "$actual"))
done

# Folder include graph: one "from to" pair per include of another folder.
folder_edges() {
  local from dir
  for dir in "$root"/libcalib/*/ "$root"/detect/ "$root"/render/ "$root"/app/; do
    from="${dir#"$root"/}"
    from="${from%/}"
    grep -ho '^#include "\(libcalib/[a-z_0-9]*\|detect\|render\|app\)/' "$dir"*.h "$dir"*.cc \
      2>/dev/null | sed 's|^#include "||; s|/$||' | grep -vx "$from" | sed "s|^|$from |" || true
  done | sort -u
}
edges="$(folder_edges)"
if ! loops="$(tsort <<<"$edges" 2>&1 >/dev/null)" || [[ -n "$loops" ]]; then
  echo "the folders include each other in a circle (each line of tsort's loop is one folder):"
  echo "$loops"
  status=1
fi

if [[ $status -eq 0 ]]; then
  echo "libcalib/CMakeLists.txt matches the include graph; no folder includes another in a circle"
fi
exit $status
