#!/usr/bin/env bash
# Builds the fuzz corpora under fuzz/corpus/<target>/ (ignored by git).
#
#   fuzz/seed.sh [DATA_DIR]
#
# Always writes the generated seeds (a small world file, ops lines, a replay script, a
# HashDAG CSV, a WAL segment from the server's own log writer, one message per request
# kind). When DATA_DIR (default: ../shared/data next to the repository) exists, it also
# adds its sample files: every .vox under DATA_DIR/vox/ up to 256 KiB, and the first 200
# rows of every HashDAG CSV under DATA_DIR/replays/ (as replay-target inputs). Sample files
# are only read; their copies go to the ignored corpus directory, never to tracked paths.
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
data="${1:-$root/../shared/data}"
corpus="$here/corpus"
export CARGO_TARGET_DIR="$here/target"

mkdir -p "$corpus"
# The seed generator shares the targets' instrumented build (it runs fine outside AFL),
# so seeding and fuzzing compile the dependencies once.
(cd "$here" && cargo afl build --quiet --release --bin seed)
"$CARGO_TARGET_DIR/release/seed" "$corpus"

if [ -d "$data" ]; then
  n=0
  if [ -d "$data/vox" ]; then
    mkdir -p "$corpus/vox"
    while IFS= read -r -d '' f; do
      name="$(basename "$(dirname "$f")")-$(basename "$f")"
      cp "$f" "$corpus/vox/data-$name"
      chmod u+w "$corpus/vox/data-$name"
      n=$((n + 1))
    done < <(find "$data/vox" -name '*.vox' -size -257k -print0)
  fi
  if [ -d "$data/replays" ]; then
    mkdir -p "$corpus/replay"
    while IFS= read -r -d '' f; do
      # Mode byte 1: a HashDAG CSV (see the replay target in fuzz/src/lib.rs).
      { printf '\001'; head -n 200 "$f"; } > "$corpus/replay/data-$(basename "$f")"
      n=$((n + 1))
    done < <(find "$data/replays" -name '*.csv' -print0)
  fi
  echo "added $n sample inputs from $data"
else
  echo "no sample data at $data: generated seeds only"
fi
for d in "$corpus"/*/; do
  echo "$(basename "$d"): $(find "$d" -type f | wc -l) inputs"
done
