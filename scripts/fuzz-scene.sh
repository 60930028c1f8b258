#!/usr/bin/env bash
# Fuzzes the scene loader with libFuzzer (Debian's clang), one job, ASan + UBSan.
#   scripts/fuzz-scene.sh [seconds]      default 600
# Seeds: scenes/*.json, every scene a run writes (physbench export-scenes, from the release build)
# and the kept regression inputs. Crashing inputs land in build/fuzz/findings/; copy each one into
# adapters/fuzz/regressions/ once fixed, where scene_tests loads it through the normal build.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-600}"
command -v clang++ >/dev/null || { echo "clang++ missing: apt-get install -y clang" >&2; exit 1; }
mkdir -p build/fuzz/corpus build/fuzz/seeds build/fuzz/findings
clang++ -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  -Iadapters/include -I/usr/include/eigen3 \
  adapters/src/scene.cpp adapters/src/scene_json.cpp adapters/fuzz/scene_fuzz.cpp \
  -o build/fuzz/scene_fuzz
cp scenes/*.json adapters/fuzz/regressions/* build/fuzz/seeds/ 2>/dev/null || true
if [ -x build/release/harness/physbench ]; then
  build/release/harness/physbench export-scenes build/fuzz/seeds >/dev/null
fi
build/fuzz/scene_fuzz -max_total_time="$seconds" -max_len=65536 -timeout=10 \
  -rss_limit_mb=2048 -artifact_prefix=build/fuzz/findings/ -print_final_stats=1 \
  build/fuzz/corpus build/fuzz/seeds
