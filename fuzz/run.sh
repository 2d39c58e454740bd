#!/usr/bin/env bash
# Runs fuzz targets one after another under AFL++, each for SECONDS, and prints what each
# run did.
#
#   fuzz/run.sh [SECONDS] [TARGET...]      (default: 600 seconds, every target)
#
# Needs `cargo install cargo-afl` (which builds AFL++ on first use) and seeded corpora
# (fuzz/seed.sh). Findings land in fuzz/out/<target>/default/{crashes,hangs}/; replay
# one with `cargo run --release --bin reproduce -- <target> <file>` (see RELIABILITY.md).
# Each run is capped at MEM_MB of memory (default 2048): an input that makes a target
# allocate past it is a crash, and a finding.
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
secs="${1:-600}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(vox world_file wal ops replay proto)
mem="${MEM_MB:-2048}"

cd "$here"
CARGO_TARGET_DIR="$here/target" cargo afl build --release
# Unattended runs: no UI, and no refusal over CPU governors or the core-dump handler,
# which only change how fast crashes are noticed.
export AFL_NO_UI=1 AFL_SKIP_CPUFREQ=1 AFL_I_DONT_CARE_ABOUT_MISSING_CRASHES=1
# A second run resumes from the first one's queue (and keeps its findings).
export AFL_AUTORESUME=1
printf '%-11s %8s %14s %10s %7s %8s %6s\n' target seconds execs execs/s corpus crashes hangs
for t in "${targets[@]}"; do
  [ -d "corpus/$t" ] || { echo "no corpus/$t: run fuzz/seed.sh first" >&2; exit 1; }
  mkdir -p "out/$t"
  # -V: stop after this many seconds; -m: memory cap in MB; -t: per-input timeout in ms.
  cargo afl fuzz -i "corpus/$t" -o "out/$t" -m "$mem" -t 2000 -V "$secs" -- "target/release/$t" \
    > "out/$t/log.txt" 2>&1 || echo "afl-fuzz for $t failed: see fuzz/out/$t/log.txt" >&2
  s="out/$t/default/fuzzer_stats"
  [ -f "$s" ] || continue
  get() { awk -F': *' -v k="$1" '$1 ~ "^"k" *$" {print $2}' "$s"; }
  printf '%-11s %8s %14s %10s %7s %8s %6s\n' "$t" "$(get run_time)" "$(get execs_done)" \
    "$(get execs_per_sec)" "$(get corpus_count)" "$(get saved_crashes)" "$(get saved_hangs)"
done
