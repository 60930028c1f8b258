#!/usr/bin/env bash
# The main job: builds the bench preset (release, native instruction set), runs the default
# suite on every engine, runs the particle benchmark against the memory roofline, and writes
# results/<timestamp>/ with results.csv, trajectories/, scenes/, metadata.json, benchmarks/ and
# index.html.
#   ./bench.sh                         the default suite
#   ./bench.sh -s tumbling-box -e rtp  any `physbench run` options pass through
#   ./bench.sh --nightly [options]     then keep the run in the history (PHYSBENCH_HISTORY, default
#                                      history/), compare it with the entry before, write the trends
#                                      page, and exit 1 on a regression (docs/regression.md)
set -euo pipefail
cd "$(dirname "$0")"
nightly=0
if [ "${1:-}" = "--nightly" ]; then
  nightly=1
  shift
fi
scripts/setup.sh
cmake --preset bench
cmake --build --preset bench
out="results/$(date +%Y%m%d-%H%M%S)"
build/bench/harness/physbench run --out "$out" "$@"
# the particle update against the memory roofline, measured in the same session (Google Benchmark)
mkdir -p "$out/benchmarks"
build/bench/bench/particles_bench --benchmark_out="$out/benchmarks/particles.json" --benchmark_out_format=json
# Repetitions of different engines are interleaved in random order, so a slow spell of the machine
# (these VMs drift by up to 2x over minutes) falls on every engine alike instead of on whichever
# ran then: the ratios between engines are what the report claims (docs/metrics.md).
interleave=(--benchmark_enable_random_interleaving=true)
# every engine's broad phase on the broadphase scene, pair sets checked (Google Benchmark)
build/bench/bench/broadphase_bench "${interleave[@]}" --benchmark_out="$out/benchmarks/broadphase.json" --benchmark_out_format=json
# every engine's narrow phase on the same random pose pairs, agreement with rtp counted (Google Benchmark)
build/bench/bench/narrowphase_bench "${interleave[@]}" --benchmark_out="$out/benchmarks/narrowphase.json" --benchmark_out_format=json
# rtp's step with contacts on the pyramid scenes, one and two threads, with per-stage shares
build/bench/bench/contacts_bench --benchmark_out="$out/benchmarks/contacts.json" --benchmark_out_format=json
# the trajectories as Parquet: the same numbers in about a third of the bytes (--export-csv brings
# the CSVs back)
.venv/bin/python reports/compact.py "$out"
.venv/bin/python reports/build_report.py "$out"
echo "bench: open $out/index.html"
if [ "$nightly" = 1 ]; then
  history="${PHYSBENCH_HISTORY:-history}"
  code=0
  .venv/bin/python reports/history.py add "$out" --history "$history" || code=$?
  .venv/bin/python reports/history.py report --history "$history"
  echo "bench: trends in $history/index.html"
  exit "$code"
fi
