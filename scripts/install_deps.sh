#!/usr/bin/env bash
# Installs meshflow's build dependencies from Debian packages (needs root or sudo).
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends \
  g++ cmake ninja-build pkg-config \
  libtbb-dev libeigen3-dev liblzf-dev \
  libspng-dev libjpeg-dev libtiff-dev \
  libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev \
  libcgal-dev libmeshoptimizer-dev libdraco-dev libopenmpi-dev openmpi-bin \
  pybind11-dev python3-dev python3-numpy python3-pytest doxygen
# The serving layer and the viewer page (`meshflow view`): Boost.Beast and Asio (headers), three.js
# (libjs-three), emscripten (the WebAssembly decoder) and Chromium (the browser test).
$SUDO apt-get install -y --no-install-recommends \
  libboost-dev libjs-three emscripten chromium
