#!/usr/bin/env bash
# Runs every test: installs what is missing, then builds and runs CTest three times — the release
# preset (every test, the report builder's pytest suite and the report in headless Chromium among
# them); the release-nosimd preset, which builds only the engine's tests with RTP_DISABLE_SIMD
# (engine/src/simd.h's scalar fallbacks) and runs those; and the debug preset with
# AddressSanitizer + UndefinedBehaviorSanitizer (the GoogleTest unit, validation and harness tests;
# not the benchmark programs, which no test runs).
#   ./test.sh               everything
#   ./test.sh --quick       release only, no sanitizer pass
#   ./test.sh -R Gates      only tests whose name matches (other arguments go to ctest)
set -euo pipefail
cd "$(dirname "$0")"
presets=(release release-nosimd debug)
if [ "${1:-}" = "--quick" ]; then
  presets=(release)
  shift
fi
scripts/setup.sh
for preset in "${presets[@]}"; do
  echo "== $preset ==" >&2
  cmake --preset "$preset"
  cmake --build --preset "$preset"
  ctest --preset "$preset" -j2 "$@"
done
