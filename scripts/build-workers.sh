#!/bin/sh
# Builds the Rust workers (workers/, docs/worker-protocol.md) with the committed lock file.
# A worker that does not build fails the build (and so CI): every worker in workers/catalog.tsv
# is part of the comparison. Without cargo CMake does not call this at all, and `physbench list`
# says which workers are missing.
#   scripts/build-workers.sh CARGO TARGET_DIR
set -u
cargo="$1"
target_dir="$2"
cd "$(dirname "$0")/../workers" || exit 1
# two jobs at most: the machines this builds on have two cores shared with others
if ! "$cargo" build --release --locked --jobs 2 --target-dir "$target_dir"; then
  echo "physbench: the Rust workers did not build (see cargo's error above)" >&2
  exit 1
fi
