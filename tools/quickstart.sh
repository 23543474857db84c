#!/usr/bin/env bash
# Quick start: installs what is missing (Debian packages), builds mpmcd (Release) and runs the main
# example, then draws its last snapshot. Usage: tools/quickstart.sh   (from anywhere)
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install_deps.sh
cmake --preset release
cmake --build --preset release --target mpmcd
out=output/squeezed_disk
./build/release/mpmcd run examples/squeezed_disk/squeezed_disk.toml -o "$out"
last=$(ls "$out"/squeezed_disk_*.vtu | tail -n 1)
/usr/bin/python3 tools/plot_points.py "$last" "$out/last_snapshot.png" --field pressure
echo "quickstart: outputs in $out (open squeezed_disk.pvd in ParaView; picture: $out/last_snapshot.png)"
