#!/usr/bin/env bash
# The installed rtscalib package as a user sees it (ctest: install_consumer).
#   run_consumer.sh CMAKE BUILD_DIR CONSUMER_SRC WORK_DIR CXX [FLAGS]
# FLAGS: compiler and linker flags the build's libraries need in a consumer
# (the sanitizers of RTSCALIB_SANITIZE); empty otherwise.
# 1. `cmake --install BUILD_DIR --prefix WORK_DIR/prefix`
# 2. configure and build tests/install/consumer with -DCMAKE_PREFIX_PATH=prefix
# 3. run it on a model.yaml written here (the ideal spherical instrument of
#    SPEC 1 with a 640x480 camera, f = 1000 px, on the line of sight, and a
#    base translation sigma), and compare with
#    - SPEC 1's ideal EDM point d [sin(phi) sin(theta), cos(phi) sin(theta), cos(theta)],
#      and the ideal pixel of a point 0.5 m right of the line of sight:
#      (cx + f 0.5 / d, cy); the EDM sigma = the base translation sigma;
#    - the installed `rtscalib predict` on the same readings.
# Tolerance 1e-9 (m, px): the ideal formulas and the model differ by rounding only.
set -euo pipefail
cmake_bin=$1 build=$2 consumer_src=$3 work=$4 cxx=$5 flags=${6:-}
rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix

"$cmake_bin" --install "$build" --prefix "$prefix" > "$work/install.log"
test -f "$prefix/include/libcalib/api/rtscalib.h"
test -f "$prefix/lib/cmake/rtscalib/rtscalibConfig.cmake" || \
  test -f "$prefix/lib64/cmake/rtscalib/rtscalibConfig.cmake"
if ls "$prefix"/include/render "$prefix"/include/app > /dev/null 2>&1; then
  echo "render/ or app/ headers were installed" >&2
  exit 1
fi

gen=()
if command -v ninja > /dev/null; then gen=(-G Ninja); fi
"$cmake_bin" -S "$consumer_src" -B "$work/build" "${gen[@]}" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="$flags" > "$work/configure.log"
"$cmake_bin" --build "$work/build" > "$work/build.log"

cat > "$work/model.yaml" <<'YAML'
format: rtscalib-model
version: 1
kinematics: spherical
edm_cyclic_unit_length: 1.5
uncertainties: true
base:
  q: [0, 0, 0, 1]
  t: [0, 0, 0]
  euler: [0, 0, 0]
  sigma: {rotation: [0, 0, 0], euler: [0, 0, 0], t: [0.001, 0.002, 0.003]}
edm:
  q: [0, 0, 0, 1]
  t: [0, 0, 0]
  euler: [0, 0, 0]
  sigma: {rotation: [0, 0, 0], euler: [0, 0, 0], t: [0, 0, 0]}
effects: []
cameras:
  - zoom: 0
    width: 640
    height: 480
    flange_from_cam:
      q: [0, 0, 0, 1]
      t: [0, 0, 0]
      euler: [0, 0, 0]
      sigma: {rotation: [0, 0, 0], euler: [0, 0, 0], t: [0, 0, 0]}
    intrinsics: {fx: 1000, fy: 1000, cx: 320, cy: 240}
    distortion: {k1: 0, k2: 0, p1: 0, p2: 0, k3: 0, k4: 0, k5: 0, k6: 0, s1: 0, s2: 0, s3: 0, s4: 0, taux: 0, tauy: 0}
    intrinsics_sigma: {fx: 0, fy: 0, cx: 0, cy: 0}
    distortion_sigma: {k1: 0, k2: 0, p1: 0, p2: 0, k3: 0, k4: 0, k5: 0, k6: 0, s1: 0, s2: 0, s3: 0, s4: 0, taux: 0, tauy: 0}
YAML

phi=0.7 theta=1.3 d=10
# 0.5 m along the camera's x axis R e_x = (cos phi, -sin phi, 0) from the EDM point.
read -r X Y Z < <(awk -v p=$phi -v t=$theta -v d=$d 'BEGIN {
  printf "%.17g %.17g %.17g\n", d*sin(p)*sin(t) + 0.5*cos(p), d*cos(p)*sin(t) - 0.5*sin(p), d*cos(t) }')
"$work/build/consumer" "$work/model.yaml" $phi $theta $d "$X" "$Y" "$Z" > "$work/consumer.txt"
cat "$work/consumer.txt"

fail=0
check() {  # check NAME GOT EXPECTED
  if ! awk -v g="$2" -v e="$3" 'BEGIN { x = g - e; if (x < 0) x = -x; exit !(x <= 1e-9) }'; then
    echo "MISMATCH $1: got $2, expected $3" >&2
    fail=1
  fi
}
field() { awk -v k="$1" -v i="$2" '$1 == k { print $(i + 1) }' "$work/consumer.txt"; }
ideal=$(awk -v p=$phi -v t=$theta -v d=$d 'BEGIN {
  printf "%.17g %.17g %.17g", d*sin(p)*sin(t), d*cos(p)*sin(t), d*cos(t) }')
read -r ex ey ez <<< "$ideal"
check edm.x "$(field edm 1)" "$ex"
check edm.y "$(field edm 2)" "$ey"
check edm.z "$(field edm 3)" "$ez"
check edm_sigma.x "$(field edm_sigma 1)" 0.001
check edm_sigma.y "$(field edm_sigma 2)" 0.002
check edm_sigma.z "$(field edm_sigma 3)" 0.003
check ray.dx "$(field ray 4)" "$(awk -v e=$ex -v d=$d 'BEGIN { printf "%.17g", e / d }')"
check ray.dz "$(field ray 6)" "$(awk -v e=$ez -v d=$d 'BEGIN { printf "%.17g", e / d }')"
check pixel.u "$(field pixel 1)" 370
check pixel.v "$(field pixel 2)" 240

# The installed binary's `predict` on the same readings.
rts="$prefix/bin/rtscalib"
printf 'face,zoom,phi,theta,tool,u,v,d,x,y,z\n1,0,%s,%s,edm,,,%s,0,0,0\n' $phi $theta $d \
  > "$work/records.csv"
printf 'face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v\n1,0,%s,%s,s,0,0,%s,%s,%s,0,0\n' \
  $phi $theta "$X" "$Y" "$Z" > "$work/pixels.csv"
"$rts" predict --model "$work/model.yaml" --records "$work/records.csv" --out "$work/rp.csv"
"$rts" predict --model "$work/model.yaml" --pixels "$work/pixels.csv" --out "$work/pp.csv"
column() {  # column FILE NAME: the value in the first data row
  awk -F, -v k="$2" 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == k) c = i; next }
                     !/^#/ { print $c; exit }' "$1"
}
check predict.x "$(field edm 1)" "$(column "$work/rp.csv" x)"
check predict.y "$(field edm 2)" "$(column "$work/rp.csv" y)"
check predict.z "$(field edm 3)" "$(column "$work/rp.csv" z)"
check predict.u "$(field pixel 1)" "$(column "$work/pp.csv" u)"
check predict.v "$(field pixel 2)" "$(column "$work/pp.csv" v)"

if [ $fail -ne 0 ]; then exit 1; fi
echo "install_consumer: installed package, consumer build and predictions agree"
