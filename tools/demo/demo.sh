#!/usr/bin/env bash
# The README's main job on built-in sample data (see README.md, Quick start).
# Foundation stage: a synthetic UMBmark square through the firmware step, both directions,
# its output frames decoded with the DBC, and a plot.
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=build/host/bin
OUT=${ODO_DEMO_OUT:-out/demo}
mkdir -p "$OUT"
for dir in cw ccw; do
  "$BIN/odo-demo" --direction "$dir" --out "$OUT/$dir"
done
echo
echo "First output frames of the cw run, decoded with can/odometry.dbc (cantools):"
head -n 6 "$OUT/cw/output.log" | .venv/bin/python -m cantools decode --single-line can/odometry.dbc
.venv/bin/odo-plot-demo --run "cw=$OUT/cw/pose.csv" --run "ccw=$OUT/ccw/pose.csv" --out "$OUT/square.png"
