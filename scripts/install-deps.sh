#!/usr/bin/env bash
# Install every build, test and benchmark dependency of scanlod from Debian 12 packages.
# Idempotent: packages already present are skipped. Works as root or through sudo.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)

packages=(
  build-essential cmake ninja-build pkg-config clang libclang-rt-14-dev
  libopenvdb-dev libboost-iostreams-dev libtbb-dev
  libopenimageio-dev libinih-dev libxxhash-dev libzstd-dev libmeshoptimizer-dev libdraco-dev
  zlib1g-dev time gnuplot-nox
  # scripts/test.sh: line and branch coverage of the test suite
  gcovr
  # scripts/bench/peers/vsa_lod.cpp: CGAL's Variational Shape Approximation (issue 12)
  libcgal-dev
  # tests/export/test_glb_render.sh: three.js in headless Chromium
  chromium
  # tests/cluster/: a throwaway single-node Slurm (its own config; no service is enabled)
  slurm-wlm munge iproute2
  # tests/export/test_html_report.sh: the HTML reports in a real (headless) browser
  chromium
)

missing=()
for p in "${packages[@]}"; do
  [ "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null)" = 'install ok installed' ] || missing+=("$p")
done
# node + npm run the Khronos glTF validator in the tests and build the HTML reports' viewer
# bundle (Debian ships npm separately).
command -v node >/dev/null || missing+=(nodejs)
command -v npm >/dev/null || missing+=(npm)

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: not root and no sudo" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
else
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The glTF validator (npm package gltf-validator, pinned by scripts/gltf/package-lock.json).
if [ ! -f "$root/scripts/gltf/node_modules/gltf-validator/package.json" ]; then
  npm ci --prefix "$root/scripts/gltf" --no-audit --no-fund --loglevel=error
fi

# The HTML reports' viewer: three.js and esbuild, bundled at build time
# (scripts/viewer/viewer.cmake), and the browser test's playwright-core, gltfpack and
# glTF-Transform (render.cjs: the GLB render test), all pinned by
# scripts/viewer/package-lock.json. Rebuild scanlod after
# this step so that the bundle gets compiled in.
if [ ! -f "$root/scripts/viewer/node_modules/.package-lock.json" ] ||
   ! cmp -s "$root/scripts/viewer/package-lock.json" "$root/scripts/viewer/node_modules/.package-lock.json.ci" 2>/dev/null; then
  npm ci --prefix "$root/scripts/viewer" --no-audit --no-fund --loglevel=error
  cp "$root/scripts/viewer/package-lock.json" "$root/scripts/viewer/node_modules/.package-lock.json.ci"
fi

# The benchmark's npm peers (scripts/bench/peers/npm/package-lock.json): meshoptimizer's
# JavaScript simplifier, the fidelity anchor (peers/meshopt_js.mjs, tests/bench/test_peers.sh),
# and gltfpack and glTF-Transform (bench_glb_size.sh).
peers=$root/scripts/bench/peers/npm
if [ ! -f "$peers/node_modules/.package-lock.json" ] ||
   ! cmp -s "$peers/package-lock.json" "$peers/node_modules/.package-lock.json.ci" 2>/dev/null; then
  npm ci --prefix "$peers" --no-audit --no-fund --loglevel=error
  cp "$peers/package-lock.json" "$peers/node_modules/.package-lock.json.ci"
fi
