#!/usr/bin/env bash
# Dense states of the paper compaction for bench/bench_compaction (docs/parallel.md, "Dense-state
# benchmark"): runs examples/paper_compaction/compaction_lambda3.toml (h = d/4: "d4") and/or
# compaction_lambda3_fine.toml (h = d/8: "d8") until [stop] phi = PHI (default 0.90), each from a
# copy of its input (and packing.csv) in build/compaction_checkpoints/lambda3_<grid>/ with that
# stop, VTU snapshots off and one checkpoint kept (the one written at the stop), and links that
# checkpoint as build/compaction_checkpoints/lambda3_<grid>.h5 for the benchmark.
# Usage (from anywhere, after the release build):
#   tools/compaction_checkpoints.sh [-t THREADS] [-p PHI] d4 [d8]
# THREADS defaults to 2. The run's log is lambda3_<grid>/run.log. Measured with 2 threads on the
# shared 2-core machine: d4 about 5 min; d8 about an hour (issue 16).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
mpmcd="${MPMCD:-$root/build/release/mpmcd}"
threads=2
phi=0.90
while getopts "t:p:" o; do
  case "$o" in
    t) threads="$OPTARG" ;;
    p) phi="$OPTARG" ;;
    *) echo "usage: $0 [-t THREADS] [-p PHI] d4|d8 ..." >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
[ $# -gt 0 ] || { echo "usage: $0 [-t THREADS] [-p PHI] d4|d8 ..." >&2; exit 2; }
[ -x "$mpmcd" ] || { echo "$mpmcd not found: build first (cmake --build --preset release)" >&2; exit 2; }
examples="$root/examples/paper_compaction"
out_root="$root/build/compaction_checkpoints"
for grid in "$@"; do
  case "$grid" in
    d4) input="$examples/compaction_lambda3.toml" ;;
    d8) input="$examples/compaction_lambda3_fine.toml" ;;
    *) echo "unknown grid '$grid' (d4 or d8)" >&2; exit 2 ;;
  esac
  dir="$out_root/lambda3_$grid"
  mkdir -p "$dir"
  cp "$examples/packing.csv" "$dir/"
  # The same input but where it stops, where it writes, no VTU and one checkpoint kept.
  sed -e "s/^phi = .*/phi = $phi/" -e 's/^folder = .*/folder = "output"\nvtu = false/' "$input" \
    > "$dir/input.toml"
  printf '\n[checkpoint]\nkeep = 1\n' >> "$dir/input.toml"
  grep -q "^phi = $phi\$" "$dir/input.toml" || { echo "no [stop] phi in $input" >&2; exit 1; }
  echo "compaction_checkpoints: $grid to phi = $phi on $threads thread(s), log in $dir/run.log"
  start=$(date +%s)
  "$mpmcd" run "$dir/input.toml" -t "$threads" --overwrite > "$dir/run.log" 2>&1 ||
    { echo "mpmcd run failed (exit $?), see $dir/run.log" >&2; exit 1; }
  checkpoint=$(ls "$dir"/output/*_checkpoint_*.h5 | sort | tail -n 1)
  ln -sfn "lambda3_$grid/output/$(basename "$checkpoint")" "$out_root/lambda3_$grid.h5"
  echo "compaction_checkpoints: $out_root/lambda3_$grid.h5 -> $checkpoint" \
    "($(($(date +%s) - start)) s; $(grep -o 'Phi = [0-9.]*' "$dir/run.log" | tail -n 1))"
done
