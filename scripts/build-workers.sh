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
# The native-instruction-set builds of the peers that compile from source here, beside their
# baseline builds (as rtp's native build runs beside its -x86-64 one): Rapier for this machine's
# CPU (-C target-cpu=native) and Box2D v3 with its AVX2 path. In a target folder of their own, so
# that neither feature nor flag reaches the baseline workers; each is copied beside them under the
# name workers/catalog.tsv gives it.
native_dir="$target_dir/native"
if ! RUSTFLAGS="-C target-cpu=native" "$cargo" build --release --locked --jobs 2 --target-dir "$native_dir" \
    -p physbench-rapier -p physbench-box2d-v3 --features physbench-box2d-v3/avx2; then
  echo "physbench: the native-instruction-set Rust workers did not build (see cargo's error above)" >&2
  exit 1
fi
cp "$native_dir/release/physbench-rapier" "$target_dir/release/physbench-rapier-native"
cp "$native_dir/release/physbench-box2d-v3" "$target_dir/release/physbench-box2d-v3-avx2"
