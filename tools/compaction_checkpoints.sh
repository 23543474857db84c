#!/usr/bin/env bash
# Dense states of the paper compaction for bench/bench_compaction (docs/parallel.md, "Dense-state
# benchmark"): runs examples/paper_compaction/compaction_lambda3.toml (h = d/4: "d4") and/or
# compaction_lambda3_fine.toml (h = d/8: "d8") until [stop] phi = PHI (default 0.90), each from a
# copy of its input (and packing.csv) in build/compaction_checkpoints/lambda3_<grid>/ with that
# stop, VTU snapshots off and one checkpoint kept (the one written at the stop), and links that
# checkpoint as build/compaction_checkpoints/lambda3_<grid>.h5 for the benchmark.
# Usage (from anywhere, after the release build):
#   tools/compaction_checkpoints.sh [-t THREADS] [-p PHI] [-r] d4 [d8]
# THREADS defaults to 1: on a machine shared with other jobs, 2 threads with libgomp's default
# wait policy are up to 20x slower than 1 in the dense state (docs/parallel.md, "Dense-state
# benchmark"). A run stopped by SIGINT/SIGTERM (Ctrl-C) writes a checkpoint; -r resumes the latest
# checkpoint in lambda3_<grid>/output (mpmcd run --restart) instead of starting anew. The run's
# log is lambda3_<grid>/run.log. MPMCD names another mpmcd binary.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
mpmcd="${MPMCD:-$root/build/release/mpmcd}"
threads=1
phi=0.90
resume=0
usage="usage: $0 [-t THREADS] [-p PHI] [-r] d4|d8 ..."
while getopts "t:p:r" o; do
  case "$o" in
    t) threads="$OPTARG" ;;
    p) phi="$OPTARG" ;;
    r) resume=1 ;;
    *) echo "$usage" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
[ $# -gt 0 ] || { echo "$usage" >&2; exit 2; }
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
  latest() { ls "$dir"/output/*_checkpoint_*.h5 2> /dev/null | sort | tail -n 1; }
  if [ "$resume" = 1 ] && [ -n "$(latest)" ]; then
    echo "compaction_checkpoints: $grid resumed from $(latest), log appended to $dir/run.log"
    run=(run --restart "$(latest)" -t "$threads")
  else
    mkdir -p "$dir"
    cp "$examples/packing.csv" "$dir/"
    # The same input but where it stops, where it writes, no VTU and one checkpoint kept.
    sed -e "s/^phi = .*/phi = $phi/" -e 's/^folder = .*/folder = "output"\nvtu = false/' "$input" \
      > "$dir/input.toml"
    printf '\n[checkpoint]\nkeep = 1\n' >> "$dir/input.toml"
    grep -q "^phi = $phi\$" "$dir/input.toml" || { echo "no [stop] phi in $input" >&2; exit 1; }
    echo "compaction_checkpoints: $grid to phi = $phi on $threads thread(s), log in $dir/run.log"
    : > "$dir/run.log"
    run=(run "$dir/input.toml" -t "$threads" --overwrite)
  fi
  start=$(date +%s)
  "$mpmcd" "${run[@]}" >> "$dir/run.log" 2>&1 ||
    { echo "mpmcd run stopped (exit $?; 4: interrupted, resume with -r), see $dir/run.log" >&2; exit 1; }
  checkpoint=$(latest)
  ln -sfn "lambda3_$grid/output/$(basename "$checkpoint")" "$out_root/lambda3_$grid.h5"
  echo "compaction_checkpoints: $out_root/lambda3_$grid.h5 -> $checkpoint" \
    "($(($(date +%s) - start)) s; $(grep -o 'Phi = [0-9.]*' "$dir/run.log" | tail -n 1))"
done
