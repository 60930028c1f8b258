#!/usr/bin/env bash
# The main job: builds the bench preset (release, native instruction set), runs the default
# suite on every engine, and writes results/<timestamp>/ with results.csv, trajectories/,
# scenes/, metadata.json and index.html.
#   ./bench.sh                         the default suite
#   ./bench.sh -s tumbling-box -e rtp  any `physbench run` options pass through
set -euo pipefail
cd "$(dirname "$0")"
scripts/setup.sh
cmake --preset bench
cmake --build --preset bench
out="results/$(date +%Y%m%d-%H%M%S)"
build/bench/harness/physbench run --out "$out" "$@"
.venv/bin/python reports/build_report.py "$out"
echo "bench: open $out/index.html"
