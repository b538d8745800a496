#!/usr/bin/env bash
# Checks that the build and the architecture document declare exactly the
# dependencies the code has (exit 1 with one line per difference):
#   1. libcalib/CMakeLists.txt: for every folder libcalib/<f>/, the libcalib
#      folders and external libraries its headers and sources #include (found
#      with grep) must equal the DEPS of its `rtscalib_add_layer(<f> DEPS ...)`.
#   2. detect/, render/, app/: the target_link_libraries of each of their
#      targets (rtscalib_detect; rtscalib_render_settings, settings.h/.cc, and
#      rtscalib_render, the rest of render/; rtscalib_app and the rtscalib
#      binary, main.cc) must equal what the target's files include.
#   3. docs/architecture.md: the "may depend on" column of every row of
#      `libcalib/<f>/`, `detect/`, `render/` and `app/` must name exactly the
#      folders and external libraries the folder's files include. The column
#      lists names separated by commas; text in parentheses is a comment; a
#      name is a folder (`fit`, `detect`, ...) or an external library (Eigen,
#      Ceres, OpenCV, yaml-cpp, nlohmann_json, VTK, apriltag, X11, CLI11);
#      "nothing" is the empty list.
#   4. No circle: a folder that includes another, directly or through others,
#      that includes it back fails, with the circle named (tsort).
# Usage: check-deps.sh [--doc FILE] (another copy of the architecture
# document, for the test that a wrong table fails). Run from anywhere; ctest
# runs it as `check_deps` and the wrong-table test as `check_deps_detects_drift`.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cmake_file="$root/libcalib/CMakeLists.txt"
doc="$root/docs/architecture.md"
if [[ $# -ge 2 && "$1" == "--doc" ]]; then
  doc="$2"
elif [[ $# -ne 0 ]]; then
  echo "usage: $0 [--doc FILE]" >&2
  exit 2
fi

# What the files include, as CMake names: rtscalib_<folder> for
# libcalib/<folder>/, rtscalib_detect, rtscalib_render_settings for
# render/settings.h, rtscalib_render, rtscalib_app, and the imported targets of
# the external libraries.
include_targets() {
  [[ $# -eq 0 ]] && return 0
  grep -ho '^#include [<"][^>"]*[>"]' "$@" 2>/dev/null | sed 's/^#include //' | awk '
    /^"libcalib\/[a-z_0-9]+\// { split(substr($0, 2), p, "/"); print "rtscalib_" p[2]; next }
    /^"render\/settings\.h"/ { print "rtscalib_render_settings"; next }
    /^"(detect|render|app)\// { split(substr($0, 2), p, "/"); print "rtscalib_" p[1]; next }
    /^<Eigen\// { print "Eigen3::Eigen"; next }
    /^<ceres\// { print "Ceres::ceres"; next }
    /^<opencv2\// { print "${OpenCV_LIBS}"; next }
    /^<yaml-cpp\// { print "yaml-cpp"; next }
    /^<nlohmann\// { print "nlohmann_json::nlohmann_json"; next }
    /^<vtk/ { print "${VTK_LIBRARIES}"; next }
    /^<(apriltag|tag[A-Za-z0-9]+)\.h>/ { print "apriltag::apriltag"; next }
    /^<X11\// { print "X11::X11"; next }
    /^<CLI\// { print "CLI11::CLI11"; next }' | sort -u
}

# The document's name of a CMake name (folder or external library).
doc_name() {
  sed 's/^rtscalib_render_settings$/render/; s/^rtscalib_//; s/^Eigen3::Eigen$/Eigen/;
       s/^Ceres::ceres$/Ceres/; s/^\${OpenCV_LIBS}$/OpenCV/; s/^nlohmann_json::nlohmann_json$/nlohmann_json/;
       s/^\${VTK_LIBRARIES}$/VTK/; s/^apriltag::apriltag$/apriltag/; s/^X11::X11$/X11/;
       s/^CLI11::CLI11$/CLI11/' | sort -u
}

# The libraries of every target_link_libraries(<target> ...) call in a CMake
# file (possibly spanning lines; PUBLIC/PRIVATE/INTERFACE dropped); apriltag's
# utilities count as apriltag.
cmake_links() {
  local file="$1" target="$2"
  awk -v t="$target" '
    { line = $0; sub(/#.*/, "", line) }
    !inside && line ~ ("target_link_libraries\\(" t "([ \t]|$)") {
      inside = 1; sub(".*target_link_libraries\\(" t, "", line) }
    inside {
      n = split(line, w, /[ \t]+/)
      for (i = 1; i <= n; i++) {
        x = w[i]
        if (x ~ /\)$/) { sub(/\)$/, "", x); done = 1 }
        if (x != "" && x != "PUBLIC" && x != "PRIVATE" && x != "INTERFACE") print x
      }
      if (done) { inside = 0; done = 0 }
    }' "$file" | sed 's/^apriltag::apriltag-utils$/apriltag::apriltag/' | sort -u
}

status=0
# compare LABEL DECLARED_IN DECLARED ACTUAL: one line per difference.
compare() {
  local label="$1" where="$2" declared="$3" actual="$4" d
  while read -r d; do
    [[ -z "$d" ]] && continue
    echo "$label: includes $d but $where does not declare it"
    status=1
  done < <(comm -13 <(echo "$declared") <(echo "$actual"))
  while read -r d; do
    [[ -z "$d" ]] && continue
    echo "$label: $where declares $d but no file includes it"
    status=1
  done < <(comm -23 <(echo "$declared") <(echo "$actual"))
}

# 1. libcalib/CMakeLists.txt against the includes.
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

declare -A folder_includes  # folder as the document names it -> what it includes (CMake names)
shopt -s nullglob
for f in $(comm -12 <(echo "$declared_folders") <(echo "$actual_folders")); do
  dir="$root/libcalib/$f"
  actual="$(include_targets "$dir"/*.h "$dir"/*.cc | grep -vx "rtscalib_$f" || true)"
  declared="$(sed -n "s/^rtscalib_add_layer($f[[:space:]]\+DEPS[[:space:]]*\(.*\))[[:space:]]*$/\1/p" \
    "$cmake_file" | tr -s ' \t' '\n' | grep -v '^$' | sort -u || true)"
  compare "libcalib/$f" "libcalib/CMakeLists.txt" "$declared" "$actual"
  folder_includes["libcalib/$f/"]="$actual"
done

# 2. detect/, render/, app/: each target's links against its files' includes.
check_target() {
  local folder="$1" target="$2"
  shift 2
  local actual declared
  actual="$(include_targets "$@" | grep -vx "$target" || true)"
  declared="$(cmake_links "$root/$folder/CMakeLists.txt" "$target")"
  compare "$folder/ ($target)" "$folder/CMakeLists.txt" "$declared" "$actual"
  folder_includes["$folder/"]+="$actual"$'\n'
}
check_target detect rtscalib_detect "$root"/detect/*.h "$root"/detect/*.cc
check_target render rtscalib_render_settings "$root"/render/settings.h "$root"/render/settings.cc
render_files=()
for file in "$root"/render/*.h "$root"/render/*.cc; do
  [[ "$(basename "$file")" == settings.* ]] || render_files+=("$file")
done
check_target render rtscalib_render "${render_files[@]}"
app_files=()
while IFS= read -r file; do
  [[ "$file" == "$root/app/main.cc" ]] || app_files+=("$file")
done < <(find "$root/app" -name '*.h' -o -name '*.cc' | sort)
check_target app rtscalib_app "${app_files[@]}"
check_target app rtscalib "$root/app/main.cc"

# 3. The "may depend on" column of docs/architecture.md against the includes.
doc_rel="${doc#"$root"/}"
known_names="$( { echo "$actual_folders"; printf '%s\n' detect render app Eigen Ceres OpenCV \
  yaml-cpp nlohmann_json VTK apriltag X11 CLI11; } | sort -u)"
# Rows as "folder<TAB>names, ...", the folder without its backticks.
doc_rows="$(awk -F'|' '{
    c = $2; gsub(/^[ \t]+|[ \t]+$/, "", c)
    if (c ~ /^`(libcalib\/[a-z_0-9]+|detect|render|app)\/`$/) { gsub(/`/, "", c); print c "\t" $4 }
  }' "$doc")"
for folder in "${!folder_includes[@]}"; do
  grep -q "^$folder"$'\t' <<<"$doc_rows" || {
    echo "$doc_rel: the table has no row for \`$folder\`"
    status=1
  }
done
while IFS=$'\t' read -r folder column; do
  [[ -z "$folder" ]] && continue
  if [[ -z "${folder_includes[$folder]+set}" ]]; then
    echo "$doc_rel: the table has a row for \`$folder\`, which is not a folder of the tree"
    status=1
    continue
  fi
  # Names: backticks and parenthesised comments dropped, split at commas, the
  # first word of each; "nothing" is none.
  listed="$(sed 's/`//g; s/([^()]*)//g' <<<"$column" | tr ',' '\n' | awk '{ print $1 }' |
    grep -v -x -e '' -e nothing | sort -u || true)"
  while read -r name; do
    [[ -z "$name" ]] && continue
    echo "$doc_rel: the row of \`$folder\` names '$name', which is neither a folder nor a known external library ($(tr '\n' ' ' <<<"$known_names"))"
    status=1
  done < <(comm -23 <(echo "$listed") <(echo "$known_names"))
  self="$(basename "$folder")"
  actual="$(grep -v '^$' <<<"${folder_includes[$folder]}" | doc_name | grep -vx "$self" || true)"
  while read -r d; do
    [[ -z "$d" ]] && continue
    echo "$folder: includes $d but its row in $doc_rel does not list it (\"may depend on\")"
    status=1
  done < <(comm -13 <(echo "$listed") <(echo "$actual"))
  while read -r d; do
    [[ -z "$d" ]] && continue
    echo "$folder: its row in $doc_rel lists $d (\"may depend on\") but no file includes it"
    status=1
  done < <(comm -23 <(comm -12 <(echo "$listed") <(echo "$known_names")) <(echo "$actual"))
done <<<"$doc_rows"

# 4. Folder include graph: one "from to" pair per include of another folder.
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
  echo "the CMake files and $doc_rel match the include graph; no folder includes another in a circle"
fi
exit $status
