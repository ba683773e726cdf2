#!/usr/bin/env bash
# The README's main job on built-in sample data (see README.md, Quick start).
# A synthetic UMBmark square through the firmware step, both directions, its output frames
# decoded with the DBC, and a plot; then the UMBmark calibration closed loop in the simulator.
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=build/host/bin
OUT=${ODO_DEMO_OUT:-out/demo}
mkdir -p "$OUT"

# The main job: a real robot's recorded runs, import -> calibrate -> write -> replay (issue 14).
bash tools/demo/realdata_demo.sh "$OUT/real"
echo
echo "Simulated robot:"
for dir in cw ccw; do
  "$BIN/odo-demo" --direction "$dir" --out "$OUT/$dir"
done
echo
echo "First output frames of the cw run, decoded with can/odometry.dbc (cantools):"
head -n 6 "$OUT/cw/output.log" | .venv/bin/python -m cantools decode --single-line can/odometry.dbc
.venv/bin/odo-plot-demo --run "cw=$OUT/cw/pose.csv" --run "ccw=$OUT/ccw/pose.csv" --out "$OUT/square.png"

# UMBmark calibration closed loop (issue 4): the 000 s. 4.6.2 robot (b 337 vs 340 mm, Ed 0.9985,
# floor roughness) runs UMBmark, odo-calib computes the correction, the firmware runs UMBmark again
# with the new parameter block; the block also goes into the Cortex-M4 image if one is built.
echo
echo "UMBmark calibration, closed loop in the simulator (000 s. 6):"
SC=host_sim/scenarios/set-sim.json
ROBOT=host_sim/robots/labmate.json
"$BIN/odo-sim" --experiment umbmark --vehicle labmate --scenario "$SC" --out "$OUT/umbmark-before" --quiet
"$BIN/odo-calib" umbmark --returns "$OUT/umbmark-before/returns.csv" --side-mm 4000 --robot "$ROBOT" \
  --out-params "$OUT/calibrated.json"
"$BIN/odo-sim" --experiment umbmark --vehicle labmate --scenario "$SC" --seed 2 \
  --params "$OUT/calibrated.json" --out "$OUT/umbmark-after" --quiet
"$BIN/odo-calib" umbmark --returns "$OUT/umbmark-after/returns.csv" --side-mm 4000 --robot "$ROBOT" \
  --params "$OUT/calibrated.json" | sed -n '1,4p'
.venv/bin/odo-plot-umbmark --before "$OUT/umbmark-before/returns.csv" \
  --after "$OUT/umbmark-after/returns.csv" --out "$OUT/umbmark.png"
if [ -f build/cm4/bin/odo_image.elf ]; then
  "$BIN/odo-calib" write --image build/cm4/bin/odo_image.elf --params "$OUT/calibrated.json" \
    --out "$OUT/odo_image-calibrated.elf"
  "$BIN/odo-calib" verify --image "$OUT/odo_image-calibrated.elf"
fi
"$BIN/odo-calib" export --params "$OUT/calibrated.json" --format ros2 > "$OUT/calibrated-ros2.yaml"
echo "ros2 diff_drive_controller multipliers: $OUT/calibrated-ros2.yaml"

# The sim-to-real gap (issue 7): "real" runs with an effect the diagnosis is not told, diagnosed
# from the recorded frames and truth alone.
echo
bash tools/demo/gap_demo.sh "$PWD/build/host" "$OUT/gap"
