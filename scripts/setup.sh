#!/usr/bin/env bash
# Installs every Debian package ShadyLoc needs (idempotent, quiet when all is
# there), then configures and builds in Release into ./build.
#   scripts/setup.sh [--no-build]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

packages=(
  cmake g++ make pkg-config
  libmrpt-obs-dev libmrpt-maps-dev libmrpt-opengl-dev libmrpt-vision-dev
  libmrpt-io-dev libmrpt-system-dev libmrpt-img-dev libmrpt-config-dev
  libmrpt-serialization-dev libmrpt-poses-dev libmrpt-math-dev libmrpt-tclap-dev
  mrpt-apps                      # rawlog-edit, RawLogViewer (integration tests)
  libopencv-dev libeigen3-dev
  libzstd-dev                    # keyframe map compression
  nlohmann-json3-dev             # the evaluation's JSON files (src/eval/Json.h)
  libgtest-dev libbenchmark-dev
  gnuplot-nox                    # calibrate-alpha and figures draw their plots with it
  libegl-mesa0 libgl1-mesa-dri   # headless offscreen rendering (EGL/Mesa)
  zlib1g-dev                     # checked gzip reading of rawlogs
  libjpeg-dev                    # libjpeg's fatal errors as exceptions (src/io/JpegErrors.cpp)
  libgif-dev                     # giflib: shadyloc localise --gif's animation (src/render/AnimatedGif.cpp)
  clang libclang-rt-14-dev       # sanitizer build and libFuzzer targets (scripts/ci-hardening.sh)
  slurm-wlm munge                # one-node Slurm cluster of the eval smoke test (scripts/slurm-smoke.sh)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] installing ${#missing[@]} Debian package(s): ${missing[*]}"
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

[ "${1:-}" = "--no-build" ] && exit 0

jobs="$(nproc 2>/dev/null || echo 2)"
cmake -S "$here" -B "$here/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$here/build" -j "$jobs"
