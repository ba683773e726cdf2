#!/usr/bin/env bash
# The demo's real-data job (issue 14): the shared OptiOdom runs (a real differential-drive robot
# with motion capture, ../shared/data/optiodom) imported, calibrated on one part, the block
# written into the Cortex-M4 image, the held-out runs replayed through the firmware with and
# without it, and a before/after plot against motion capture.
# usage: realdata_demo.sh OUT   (ODO_OPTIODOM overrides the data folder)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:?usage: realdata_demo.sh OUT}
BIN=build/host/bin
DATA=${ODO_OPTIODOM:-../shared/data/optiodom}
ROBOT=tools/python/odo_tools/gap/robots/optiodom.json
if [ ! -d "$DATA/square-230620202042" ]; then
  echo "real data: $DATA not found (set ODO_OPTIODOM); skipping the real-data job"
  exit 0
fi
mkdir -p "$OUT"
echo "Real robot data (OptiOdom, $DATA): import -> calibrate -> write -> replay"
.venv/bin/odo-import ticks-csv --ticks "$DATA/square-230620202042" "$DATA/circular-250620202104" \
  --columns time,x,y,theta,right,left --directions cw,cw,cw,ccw,ccw,ccw \
  --robot "$ROBOT" --out "$OUT/import" 2>/dev/null
SQ=$OUT/import/square-230620202042 CI=$OUT/import/circular-250620202104
# fitted on squares 1, 2, 4, 5 and circles 1, 2, 4; judged on squares 3, 6 and circles 3, 5, 6
"$BIN/odo-calib" fit --runs "$SQ" "$CI" --robot "$ROBOT" \
  --fit 'square*/run-*-0[12]' 'circ*/run-cw-0[12]' 'circ*/run-ccw-01' \
  --out-params "$OUT/optiodom.json" "$OUT/optiodom.bin" 2>/dev/null | tee "$OUT/fit.txt"
if command -v arm-none-eabi-gcc >/dev/null; then   # incremental: the image of this firmware
  cmake --preset cm4 >/dev/null && cmake --build --preset cm4 -j 2 >/dev/null
fi
PARAMS_AFTER="$OUT/optiodom.json"
if [ -f build/cm4/bin/odo_image.elf ]; then
  "$BIN/odo-calib" write --image build/cm4/bin/odo_image.elf --params "$OUT/optiodom.bin" \
    --out "$OUT/odo_image-optiodom.elf"
  "$BIN/odo-calib" verify --image "$OUT/odo_image-optiodom.elf"
  # replay with the block as it sits in the image
  "$BIN/odo-calib" read --image "$OUT/odo_image-optiodom.elf" --json > "$OUT/from-image.json"
  PARAMS_AFTER="$OUT/from-image.json"
fi
runs=()
mkdir -p "$OUT/replay"
for r in "$SQ/run-cw-03" "$SQ/run-ccw-03" "$CI/run-cw-03" "$CI/run-ccw-02" "$CI/run-ccw-03"; do
  set="$(basename "$(dirname "$r")")"; set=${set%%-*}; name="$set/$(basename "$r")"
  "$BIN/odo-replay" --quiet --log "$r.log" --robot "$ROBOT" --out "$OUT/replay/$set-$(basename "$r")-before"
  "$BIN/odo-replay" --quiet --log "$r.log" --params "$PARAMS_AFTER" --out "$OUT/replay/$set-$(basename "$r")-after"
  runs+=(--run "$name=$r.truth.csv,$OUT/replay/$set-$(basename "$r")-before/poses.csv,$OUT/replay/$set-$(basename "$r")-after/poses.csv")
done
.venv/bin/odo-plot-realdata "${runs[@]}" --out "$OUT/heldout.png"
"$BIN/odo-calib" export --params "$OUT/optiodom.json" --format ros2 --controller-name optiodom_base \
  > "$OUT/optiodom-ros2.yaml"
echo "held-out trajectories: $OUT/heldout.png; ros2 parameters: $OUT/optiodom-ros2.yaml"
