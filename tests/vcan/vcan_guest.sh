#!/bin/sh
# The real-kernel vcan test (issue 6 item 4), run inside the qemu guest by /init (or on a host
# whose kernel has vcan, by vcan_qemu.sh --host). POSIX sh + busybox + can-utils only.
#
# Environment: D = folder with in.log (sensor frames), robot.json, expected.txt (ID#DATA of the
# offline replay's output frames, host build), REPLAY = odo-replay binary, IF = vcan interface to
# create. Prints progress lines "vcan: ..." and exactly one verdict line:
#   ODO-VCAN-VERDICT: PASS frames=N ticks=M ...      or      ODO-VCAN-VERDICT: FAIL <reason>
# (FAIL-TIMING: a sensor frame reached the bus more than half a period late and the capture lost
# frames or the live tick timer passed one: the emulator was starved, not the code wrong)
set -u
D=${D:-/test}
REPLAY=${REPLAY:-/bin/odo-replay}
IF=${IF:-vcan0}
W=${W:-/tmp/vcan-work}
rm -rf "$W"
mkdir -p "$W"

fail() {
    echo "ODO-VCAN-VERDICT: FAIL $*"
    exit 1
}

ip link add dev "$IF" type vcan || fail "cannot create $IF (no vcan in this kernel?)"
ip link set "$IF" up || fail "cannot bring $IF up"
echo "vcan: $IF up"

# Bad input on a real stack: a missing interface and an interface that is down.
if "$REPLAY" --iface nosuch0 --robot "$D/robot.json" --quiet 2>"$W/nosuch.err"; then
    fail "odo-replay accepted a missing interface"
fi
grep -q "no interface 'nosuch0'" "$W/nosuch.err" || fail "missing-interface message: $(cat "$W/nosuch.err")"
ip link add dev "${IF}d" type vcan || fail "cannot create ${IF}d"
if "$REPLAY" --iface "${IF}d" --robot "$D/robot.json" --quiet 2>"$W/down.err"; then
    fail "odo-replay accepted an interface that is down"
fi
grep -q "is down" "$W/down.err" || fail "interface-down message: $(cat "$W/down.err")"
ip link del "${IF}d"
echo "vcan: bad-input checks passed"

# In-guest offline replay of the same log with the guest build: same frames as the host build.
"$REPLAY" --log "$D/in.log" --robot "$D/robot.json" --out "$W/offline" --quiet || fail "offline replay failed"
awk '{print $3}' "$W/offline/out.log" >"$W/offline.txt"
cmp -s "$W/offline.txt" "$D/expected.txt" || fail "guest offline replay differs from the host's"

# Live: capture the bus, start odo-replay, play the log with its timing, compare frame by frame.
candump -L "$IF,180:780" >"$W/bus.log" 2>"$W/candump.err" &
CANDUMP=$!
candump -L "$IF,100:780" >"$W/sensors.log" 2>/dev/null &
CANDUMP2=$!
"$REPLAY" --iface "$IF" --robot "$D/robot.json" --out "$W/live" --idle-exit 1.5 2>"$W/live.err" &
LIVE=$!
n=0
until grep -q "listening on $IF" "$W/live.err" 2>/dev/null; do
    n=$((n + 1))
    [ "$n" -lt 100 ] || fail "odo-replay did not start: $(cat "$W/live.err")"
    sleep 0.1
done
# Warm-up: under TCG the first run of a code path (canplayer, the kernel's CAN send path) is
# translated first and can take tens of ms, more than the half period a frame may be late. Frames
# with an identifier odo-replay does not consume, so its kernel filter drops them.
awk '{sub(/ [0-9A-F]+#[0-9A-F]*$/, " 7FF#0000"); print}' "$D/in.log" | head -40 >"$W/warm.log"
canplayer -I "$W/warm.log" "$IF=can0" || fail "canplayer (warm-up) failed"
sleep 0.2
canplayer -I "$D/in.log" "$IF=can0" || fail "canplayer failed"
echo "vcan: canplayer done"
wait "$LIVE" || fail "live odo-replay exited with an error: $(cat "$W/live.err")"
# the captures can trail a starved guest by seconds (a clean-clone CI run cut the output capture
# at 642 of 750 frames after a fixed 0.3 s): wait until they hold what was sent, 10 s at most
n=0
until [ "$(wc -l <"$W/bus.log")" -ge "$(wc -l <"$W/live/out.log")" ] &&
    [ "$(wc -l <"$W/sensors.log")" -ge "$(wc -l <"$D/in.log")" ]; do
    n=$((n + 1))
    [ "$n" -lt 100 ] || break
    sleep 0.1
done
sleep 0.3
kill "$CANDUMP" "$CANDUMP2" 2>/dev/null
wait "$CANDUMP" 2>/dev/null
wait "$CANDUMP2" 2>/dev/null

# How late the kernel stamped each sensor frame against the log's timing (first frame = 0): the
# replay accepts up to half a period (20 ms). Beyond that a starved emulator, not the code, moved
# frames to other ticks; the live replay must then equal the offline replay of the traffic as the
# kernel stamped it (sensors.log: the same SO_TIMESTAMP odo-replay reads), which holds however
# slow the guest is. Only a capture that lost frames, or a frame the live tick timer had already
# passed, says FAIL-TIMING (vcan_qemu.sh runs the guest once more).
jitter=$(awk 'NR == FNR { a[FNR] = substr($1, 2, length($1) - 2); next }
    { b = substr($1, 2, length($1) - 2); if (FNR == 1) { a0 = a[1]; b0 = b }
      d = (b - b0) - (a[FNR] - a0); if (d < 0) d = -d; if (d > m) m = d }
    END { printf "%.1f", m * 1000 }' "$D/in.log" "$W/sensors.log")
echo "vcan: largest bus delay of a sensor frame vs the log's timing: $jitter ms"
awk '{print $3}' "$W/bus.log" >"$W/bus.txt"
awk '{print $3}' "$W/live/out.log" >"$W/live.txt"
frames=$(wc -l <"$D/expected.txt" | tr -d ' ')
bus=$(wc -l <"$W/bus.txt" | tr -d ' ')
[ "$frames" -gt 0 ] || fail "no expected frames"
ref="$D/expected.txt"
ref_poses="$W/offline/poses.csv"
if awk -v j="$jitter" 'BEGIN { exit !(j > 20) }'; then
    awk '{print $3}' "$D/in.log" >"$W/sent.txt"
    awk '{print $3}' "$W/sensors.log" >"$W/seen.txt"
    if ! cmp -s "$W/sent.txt" "$W/seen.txt" || ! grep -q '"late": 0,' "$W/live/summary.json"; then
        # a lost capture, or a frame after the live tick timer had closed its tick (offline has
        # no timer): the starved emulator decided, nothing left to compare against
        echo "ODO-VCAN-VERDICT: FAIL-TIMING frames lost or late while one was delayed $jitter ms"
        exit 1
    fi
    "$REPLAY" --log "$W/sensors.log" --robot "$D/robot.json" --out "$W/bustimed" --quiet ||
        fail "offline replay of the captured bus failed"
    awk '{print $3}' "$W/bustimed/out.log" >"$W/bustimed.txt"
    ref="$W/bustimed.txt"
    ref_poses="$W/bustimed/poses.csv"
    echo "vcan: frames delayed beyond half a period: judged against the offline replay of the bus as the kernel stamped it"
fi
if ! cmp -s "$W/bus.txt" "$ref"; then
    echo "vcan: first differences (expected vs bus):"
    diff "$ref" "$W/bus.txt" | head -20 | sed 's/^/vcan:   /'
    echo "vcan: first sensor frames as the kernel stamped them:"
    head -12 "$W/sensors.log" | sed 's/^/vcan:   /'
    echo "vcan: live summary $(cat "$W/live/summary.json")"
    head -n "$bus" "$ref" >"$W/ref_head.txt"
    if [ "$bus" -lt "$(wc -l <"$ref")" ] && cmp -s "$W/bus.txt" "$W/ref_head.txt"; then
        echo "ODO-VCAN-VERDICT: FAIL-TIMING the bus capture stopped at $bus frames, all of them right"
        exit 1
    fi
    fail "bus frames differ from the offline replay ($bus vs $(wc -l <"$ref" | tr -d ' ') frames)"
fi
cmp -s "$W/live.txt" "$ref" || fail "live out.log differs from the offline replay"
cmp -s "$W/live/poses.csv" "$ref_poses" || fail "live poses.csv differs from the offline one"
ticks=$(($(wc -l <"$W/offline/poses.csv") - 1))
echo "vcan: live summary $(cat "$W/live/summary.json")"

# Interface down and up again while odo-replay listens: it reports it and carries on.
"$REPLAY" --iface "$IF" --robot "$D/robot.json" --out "$W/updown" --idle-exit 1.0 --no-send 2>"$W/updown.err" &
LIVE=$!
n=0
until grep -q "listening on $IF" "$W/updown.err" 2>/dev/null; do
    n=$((n + 1))
    [ "$n" -lt 100 ] || fail "odo-replay did not start: $(cat "$W/updown.err")"
    sleep 0.1
done
cansend "$IF" 110#0000000000000000
ip link set "$IF" down
sleep 0.3
ip link set "$IF" up
sleep 0.3
cansend "$IF" 110#1000001000000100
cansend "$IF" 20000040#0000000000000000
wait "$LIVE" || fail "odo-replay did not survive the interface going down: $(cat "$W/updown.err")"
grep -q '"down_events": [1-9]' "$W/updown/summary.json" || fail "down event not counted: $(cat "$W/updown/summary.json")"
grep -q '"bus_off": 1' "$W/updown/summary.json" || fail "bus-off error frame not seen: $(cat "$W/updown/summary.json")"
grep -q '"sensor_frames": 2' "$W/updown/summary.json" || fail "frames after the interface came back lost: $(cat "$W/updown/summary.json")"
echo "vcan: down/up recovery passed"

echo "ODO-VCAN-VERDICT: PASS frames=$frames ticks=$ticks max_delay_ms=$jitter kernel=$(uname -r)"
