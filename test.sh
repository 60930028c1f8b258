#!/usr/bin/env bash
# Runs every test: installs what is missing, builds the release preset, runs CTest
# (GoogleTest unit, validation and harness tests, and the report builder's pytest suite).
#   ./test.sh            all tests
#   ./test.sh -R Gates   only tests whose name matches (any ctest arguments pass through)
set -euo pipefail
cd "$(dirname "$0")"
scripts/setup.sh
cmake --preset release
cmake --build --preset release
ctest --preset release -j2 "$@"
