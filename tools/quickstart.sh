#!/usr/bin/env bash
# Quick start: installs what is missing (Debian packages), builds mpmcd (Release) and runs the main
# example, a scaled-down compaction of 40 soft disks (examples/quick_compaction), then fits the
# compaction law (mpmcd analyze) and draws the grains like the paper's Figure 3: coloured by grain
# pressure with the contact-force network at Phi = 0.78, 0.9, 0.97 (PNG and PDF), and in distinct
# colours (neighbours never share one) at Phi = 0.97 (docs/observables.md, "Pictures").
# Usage: tools/quickstart.sh   (from anywhere)
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install_deps.sh
cmake --preset release
cmake --build --preset release --target mpmcd
out=output/quick_compaction
./build/release/mpmcd run examples/quick_compaction/quick_compaction.toml -o "$out" --overwrite
./build/release/mpmcd analyze "$out" -o "$out/analysis" --overwrite
/usr/bin/python3 tools/plot_snapshots.py "$out" --phi 0.78 0.9 0.97 --field pressure --forces \
  --format png pdf -o "$out/snapshots"
/usr/bin/python3 tools/plot_snapshots.py "$out" --phi 0.97 --field grain -o "$out/snapshots"
echo "quickstart: outputs in $out (time series quick_compaction.csv, quick_compaction.pvd for" \
  "ParaView, analysis/figure4.png and figure5.png, snapshots/*.png and *.pdf)"
