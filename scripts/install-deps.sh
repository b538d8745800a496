#!/usr/bin/env bash
# Installs the Debian packages rtscalib builds and runs with (Debian 12 "bookworm").
# Idempotent: packages already present are skipped, so a second run costs a few seconds.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libceres-dev libopencv-dev
  # Eigen's large products through BLAS (cmake/eigen_blas.cmake): OpenBLAS's
  # threaded build, the one safe to call from several threads at once (each
  # call then runs on its caller's thread: cmake/blas_threads.cc)
  libopenblas0-pthread
  # detect/ uses OpenCV's aruco module (ChArUco boards); libopencv-dev pulls it in, named here
  libopencv-contrib-dev
  libvtk9-dev libapriltag-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  # tests/export reads the exported URDF back with KDL
  liburdfdom-dev liborocos-kdl-dev libkdl-parser-dev
  xvfb xauth libgl1-mesa-dri libglx-mesa0 mesa-utils
  # headless browser: scripts/render-report.sh checks report.html in it
  chromium
  # figures (app/plot/vega.h): Vega 5's modules, inlined in report.html (and run
  # by node in tests/app/vega_svg_test.cc, against rtscalib's own SVG
  # drawing); librsvg (loaded by rtscalib, app/plot/svg_raster.h) draws the PNG
  # files from the SVG files, libdeflate compresses them
  libjs-vega nodejs librsvg2-2 libdeflate0
  # tests/independent: photos from a renderer written from SPEC.md alone
  python3-numpy python3-opencv python3-yaml
  # OpenCV's own sample photos of a real camera (examples/data/left*.jpg):
  # configs/bench.yaml and tests/app/opencv_sample_photos_test.cc
  opencv-doc
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
# The package lists a machine already has are tried first: a package added
# to this list since the last run installs without refreshing them.
if ! "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null 2>&1; then
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
echo "install-deps: done"
