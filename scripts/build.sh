#!/usr/bin/env bash
# Configures and builds the package standalone (devel space in build/devel), Release by default.
set -euo pipefail
source "$(dirname "$0")/env.sh"
cmake -S "$SPINNING_TOP_ROOT" -B "$SPINNING_TOP_BUILD" \
  -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE="${CMAKE_BUILD_TYPE:-Release}" >/dev/null
cmake --build "$SPINNING_TOP_BUILD" -- -j"$(nproc)"
