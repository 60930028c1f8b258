#!/bin/sh
# Builds the Rust workers (workers/, docs/worker-protocol.md) with the committed lock file.
# Never fails: without a worker the harness still runs, and `physbench list` says what is missing.
#   scripts/build-workers.sh CARGO TARGET_DIR
cargo="$1"
target_dir="$2"
cd "$(dirname "$0")/../workers" || exit 0
# two jobs at most: the machines this builds on have two cores shared with others
if ! "$cargo" build --release --locked --jobs 2 --target-dir "$target_dir"; then
  echo "physbench: the Rust workers did not build (see above); the harness runs without them" >&2
fi
exit 0
