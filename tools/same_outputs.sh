#!/bin/bash
# Refactoring check (issue 15, docs/parallel.md): runs a set of short inputs (serial examples cut
# with --stop-after, the MPI tests' inputs on 1 and 2 ranks, both schemes) with two mpmcd binaries
# and compares every CSV, VTU and PVD byte for byte, the checkpoints' datasets with h5dump
# (Debian hdf5-tools) but for /meta/mpmcd_version (the binary's name), and the timers' CSV only
# by stage names.
# Usage: tools/same_outputs.sh OLD_BINARY NEW_BINARY [WORKDIR]; exit 0 when all are identical.
set -u
if [ $# -lt 2 ] || [ ! -x "$1" ] || [ ! -x "$2" ]; then
  echo "usage: tools/same_outputs.sh OLD_BINARY NEW_BINARY [WORKDIR] (two executable mpmcd binaries)" >&2
  exit 2
fi
command -v h5dump >/dev/null || { echo "same_outputs.sh: h5dump not found (apt-get install hdf5-tools)" >&2; exit 2; }
old=$1; new=$2; work=${3:-/tmp/mpmcd_same_outputs}
root=$(cd "$(dirname "$0")/.." && pwd)
mpirun_cmd=(mpirun --oversubscribe -np 2)
[ "$(id -u)" = 0 ] && mpirun_cmd+=(--allow-run-as-root)
runs() {  # runs BINARY TAG
  local bin=$1 out=$work/$2
  rm -rf "$out"; mkdir -p "$out"
  one() { local name=$1; shift; "$bin" run -q -t 1 --overwrite -o "$out/$name" "$@" >"$out/$name.log" 2>&1; echo "$name rc $?" >>"$out/rc.txt"; }
  one quick "$root/examples/quick_compaction/quick_compaction.toml" --stop-after 300
  one paper "$root/examples/paper_compaction/compaction_lambda3_coarse.toml" --stop-after 200
  one squeeze "$root/examples/squeezed_disk/squeezed_disk.toml" --stop-after 100
  one iso "$root/examples/isotropic_compaction/isotropic_compaction_ci.toml" --stop-after 100
  one mpi1 "$root/tests/mpi/compaction_mpi.toml"
  one fail1 "$root/tests/mpi/failure_mpi.toml"
  one load1 "$root/tests/mpi/loading_mpi.toml"
  if command -v mpirun >/dev/null; then
    for s in partition master; do
      "${mpirun_cmd[@]}" "$bin" run -q -t 1 --overwrite --scheme $s -o "$out/mpi2_$s" \
        "$root/tests/mpi/compaction_mpi.toml" >"$out/mpi2_$s.log" 2>&1
      echo "mpi2_$s rc $?" >>"$out/rc.txt"
    done
    "${mpirun_cmd[@]}" "$bin" run -q -t 1 --overwrite -o "$out/load2" \
      "$root/tests/mpi/loading_mpi.toml" >"$out/load2.log" 2>&1
    echo "load2 rc $?" >>"$out/rc.txt"
  fi
}
runs "$old" old
runs "$new" new
status=0
if ! cmp -s "$work/old/rc.txt" "$work/new/rc.txt"; then
  echo "exit codes differ:"; paste "$work/old/rc.txt" "$work/new/rc.txt"; status=1
fi
dump() {  # dump FOLDER FILE: the checkpoint's datasets as text, without /meta/mpmcd_version
  (cd "$1" && h5dump "$2") | sed '/DATASET "mpmcd_version"/,/^      }$/d'
}
files=0
while IFS= read -r f; do
  rel=${f#"$work/old/"}
  files=$((files + 1))
  if [[ $rel == *_timers.csv ]]; then
    cmp -s <(cut -d, -f1 "$f") <(cut -d, -f1 "$work/new/$rel") || { echo "timer stages differ: $rel"; status=1; }
  elif [[ $rel == *.h5 ]]; then
    cmp -s <(dump "$work/old" "$rel") <(dump "$work/new" "$rel") ||
      { echo "checkpoint differs: $rel"; status=1; }
  elif ! cmp -s "$f" "$work/new/$rel"; then
    echo "differs: $rel"; status=1
  fi
done < <(find "$work/old" -mindepth 2 \( -name '*.csv' -o -name '*.vtu' -o -name '*.pvd' -o -name '*.h5' \) | sort)
echo "$files files compared in $work (old/ and new/): $([ $status = 0 ] && echo identical || echo DIFFERENT)"
exit $status
