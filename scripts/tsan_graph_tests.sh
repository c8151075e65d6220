#!/usr/bin/env bash
# Runs the flow-graph tests under ThreadSanitizer. TSan only sees synchronization in
# instrumented code, and Debian's libtbb is not instrumented (every task hand-off would look
# like a race), so this builds oneTBB from Debian's own source package with TBB_SANITIZE=thread
# first, then meshflow against it. Needs root or sudo (adds a deb-src entry). Build dir: build-tsan/.
# The serving layer (Boost.Asio) is left out here (-DMESHFLOW_SERVE=OFF): GCC refuses its
# atomic_thread_fence under -fsanitize=thread; its tests run under ASan + UBSan.
set -euo pipefail
cd "$(dirname "$0")/.."
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
work="$PWD/build-tsan"
mkdir -p "$work"

if ! apt-get source --help >/dev/null 2>&1 || ! grep -rqs "deb-src" /etc/apt/sources.list /etc/apt/sources.list.d/; then
  printf 'Types: deb-src\nURIs: http://deb.debian.org/debian\nSuites: bookworm\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' |
    $SUDO tee /etc/apt/sources.list.d/meshflow-deb-src.sources >/dev/null
  $SUDO apt-get update
fi
$SUDO apt-get install -y --no-install-recommends dpkg-dev xz-utils

if [ ! -f "$work/tbb-install/lib/cmake/TBB/TBBConfig.cmake" ]; then
  (cd "$work" && rm -rf tbb-src && mkdir tbb-src && cd tbb-src && apt-get source --download-only onetbb &&
   tar xf onetbb_*.orig.tar.xz)
  src=$(find "$work/tbb-src" -maxdepth 1 -mindepth 1 -type d | head -n 1)
  cmake -S "$src" -B "$work/tbb-build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTBB_TEST=OFF \
    -DTBB_SANITIZE=thread -DTBB_STRICT=OFF -DCMAKE_INSTALL_PREFIX="$work/tbb-install" -DCMAKE_INSTALL_LIBDIR=lib \
    -DTBBMALLOC_BUILD=OFF -DTBB_DISABLE_HWLOC_AUTOMATIC_SEARCH=ON  # sanitized builds use neither
  cmake --build "$work/tbb-build"
  cmake --install "$work/tbb-build"
fi

cmake -S . -B "$work/meshflow" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMESHFLOW_WERROR=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DMESHFLOW_SANITIZE=thread -DMESHFLOW_GRAPH_TESTS_ONLY=ON -DMESHFLOW_BUILD_BENCHMARKS=OFF -DMESHFLOW_WITH_MPI=OFF -DMESHFLOW_SERVE=OFF -DCMAKE_UNITY_BUILD=ON -DCMAKE_PREFIX_PATH="$work/tbb-install" \
  -DTBB_DIR="$work/tbb-install/lib/cmake/TBB"
cmake --build "$work/meshflow"
# Every graph test, the real-data ones included (the unity builds of .ci/run left the time for
# them: ~25 s more under TSan).
TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$PWD/scripts/tsan.supp" \
  ctest --test-dir "$work/meshflow" --output-on-failure -j2 -R 'Pipeline|SequenceRunner|DepthPath|Reconstruction\.Same|Cli\.Run|Cli\.Profile'
