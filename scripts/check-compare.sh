#!/usr/bin/env bash
# The end-to-end check of `physbench compare` on real runs (a benchmark, not a test: its outcome
# depends on the machine). Runs the contact stacks three times with the given build: twice as built
# and once with ENGINE[/VARIANT]'s timed stepping stretched by SHARE (PHYSBENCH_TEST_SLOWDOWN), then
# compares the first with each. Expect "no change beyond the noise" for the second run and the
# stretched engine's rows `slower` (docs/regression.md).
#   scripts/check-compare.sh [BUILD_DIR] [ENGINE[/VARIANT]:SHARE]    (default build/release rtp:0.15)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build/release}"
slowdown="${2:-rtp:0.15}"
out=$(mktemp -d)
args=(-s tower-20,pyramid-10,pyramid-20 -e rtp,bullet,jolt,physx,box3d --variant soft-step,float,default,pgs --no-sweep)
"$build/harness/physbench" run "${args[@]}" -o "$out/old" >/dev/null
"$build/harness/physbench" run "${args[@]}" -o "$out/same" >/dev/null
PHYSBENCH_TEST_SLOWDOWN="$slowdown" "$build/harness/physbench" run "${args[@]}" -o "$out/slowed" >/dev/null
echo "== the same build twice"
"$build/harness/physbench" compare "$out/old" "$out/same" || true
echo "== $slowdown"
"$build/harness/physbench" compare "$out/old" "$out/slowed" || true
echo "(runs in $out)"
