#!/usr/bin/env bash
# The real-kernel vcan test (issue 6 item 4): replay a simulator log over a real Linux CAN stack
# and compare odo-replay's live output, frame by frame, with the offline replay of the same log.
#
#   tests/vcan/vcan_qemu.sh BUILD_DIR [SOURCE_DIR]          (ctest: vcan.qemu_replay)
#
# This machine's kernel has no CAN (AF_CAN: errno 97), so the test boots Debian's stock kernel
# (linux-image-amd64) under qemu-system-x86_64 with a generated initramfs: busybox-static, the
# can, can-raw, can-dev and vcan modules of that kernel (and what modinfo says they depend on),
# can-utils, and odo-replay-guest (unsanitised) with its shared libraries. The guest runs
# tests/vcan/vcan_guest.sh and prints its verdict on the serial console; this script parses it.
# KVM is used when it works, TCG otherwise. Where the host kernel can create a vcan interface
# (and we are root) the guest script runs on the host directly instead (ODO_VCAN_MODE=qemu forces
# qemu, =host forces the host).
#
# The kernel package is downloaded once (apt-get download) into ODO_VCAN_CACHE (default
# SOURCE_DIR/build/vcan-cache) and reused. Nothing is skipped: a missing tool is a failure with
# the reason (tools/deps.sh installs them all).
set -euo pipefail

B=$(cd "${1:?usage: vcan_qemu.sh BUILD_DIR [SOURCE_DIR]}" && pwd)
S=$(cd "${2:-$(dirname "$0")/../..}" && pwd)
CACHE=${ODO_VCAN_CACHE:-$S/build/vcan-cache}
W=$B/vcan
LOG_SECONDS=${ODO_VCAN_LOG_SECONDS:-5}
MODE=${ODO_VCAN_MODE:-auto}
T0=$(date +%s.%N)

say() { echo "vcan_qemu: $*"; }
die() { echo "vcan_qemu: FAIL: $*" >&2; exit 1; }

for tool in qemu-system-x86_64 cpio gzip candump canplayer cansend apt-get dpkg-deb; do
    command -v "$tool" >/dev/null || die "$tool not found (run tools/deps.sh)"
done
BUSYBOX=$(command -v busybox || true)
[ -n "$BUSYBOX" ] || die "busybox not found (busybox-static; run tools/deps.sh)"
for bin in odo-sim odo-replay odo-replay-guest; do
    [ -x "$B/bin/$bin" ] || die "$B/bin/$bin not built"
done

rm -rf "$W"
mkdir -p "$W/data"

# 1. The input: the first LOG_SECONDS of a clapper straight-36m run from the simulator, on the
#    fixed epoch 0 (the awk below cuts by time since the start).
"$B/bin/odo-sim" --experiment straight-36m --vehicle clapper --scenario "$S/host_sim/scenarios/none.json" \
    --runs 1 --quiet --log-start 0 --out "$W/sim" >/dev/null
awk -v lim="$LOG_SECONDS" '{t = substr($1, 2, length($1) - 2) + 0; if (t < lim) print}' \
    "$W/sim/run-fwd-01.log" >"$W/data/in.log"
cp "$S/host_sim/robots/clapper.json" "$W/data/robot.json"
[ -s "$W/data/in.log" ] || die "empty sim log"

# 2. The reference: the offline replay on the host (the sanitised build).
"$B/bin/odo-replay" --log "$W/data/in.log" --robot "$W/data/robot.json" --out "$W/offline" --quiet
awk '{print $3}' "$W/offline/out.log" >"$W/data/expected.txt"
say "input $(wc -l <"$W/data/in.log") sensor frames, expecting $(wc -l <"$W/data/expected.txt") output frames"

# 3a. Host kernel with vcan: run the guest script here.
host_has_vcan() {
    [ "$(id -u)" -eq 0 ] || return 1
    ip link add dev odovcanprobe type vcan 2>/dev/null || { modprobe vcan 2>/dev/null &&
        ip link add dev odovcanprobe type vcan 2>/dev/null; } || return 1
    ip link del odovcanprobe
}
if [ "$MODE" = host ] || { [ "$MODE" = auto ] && host_has_vcan; }; then
    say "host kernel has vcan: running the test on the host"
    out=$(D="$W/data" REPLAY="$B/bin/odo-replay-guest" IF=odovcan$$ W="$W/host" sh "$S/tests/vcan/vcan_guest.sh" 2>&1) || true
    echo "$out"
    ip link del "odovcan$$" 2>/dev/null || true
    echo "$out" | grep -q "^ODO-VCAN-VERDICT: PASS" || die "host run did not pass"
    exit 0
fi

# 3b. Debian's kernel, downloaded once.
mkdir -p "$CACHE"
if [ ! -s "$CACHE/vmlinuz" ] || [ ! -s "$CACHE/modules.list" ]; then
    say "fetching Debian's linux-image-amd64 into $CACHE (once)"
    rm -rf "$CACHE/dl" && mkdir -p "$CACHE/dl"
    if ! (cd "$CACHE/dl" && apt-get download linux-image-amd64 >/dev/null 2>&1); then
        # stale or missing package lists: refresh them once (root), then try again
        [ "$(id -u)" -eq 0 ] && apt-get update -qq >/dev/null 2>&1 || true
        (cd "$CACHE/dl" && apt-get download linux-image-amd64 >/dev/null 2>&1) ||
            die "apt-get download linux-image-amd64 failed (network? apt sources?)"
    fi
    dep=$(dpkg-deb -f "$CACHE"/dl/linux-image-amd64_*.deb Depends | tr ',' '\n' | grep -o 'linux-image-[0-9][^ ]*' | head -1)
    [ -n "$dep" ] || die "cannot read the kernel package linux-image-amd64 depends on"
    (cd "$CACHE/dl" && apt-get download "$dep" >/dev/null 2>&1) || die "apt-get download $dep failed"
    rm -rf "$CACHE/x" && dpkg-deb -x "$CACHE"/dl/"$dep"_*.deb "$CACHE/x"
    kver=$(ls "$CACHE/x/lib/modules" | head -1)
    cp "$CACHE/x/boot/vmlinuz-$kver" "$CACHE/vmlinuz.new"
    # The modules and, recursively, what each one's modinfo "depends=" names (no modules.dep in
    # the package: depmod runs at install time). Load order: dependencies first.
    mods=$(find "$CACHE/x/lib/modules/$kver" -name '*.ko*')
    order=""
    add_mod() {
        local name=$1 f dep
        case " $order " in *" $name "*) return ;; esac
        f=$(echo "$mods" | grep -E "/${name//[-_]/[-_]}\.ko(\.xz|\.zst|\.gz)?$" | head -1)
        [ -n "$f" ] || die "module $name not in $dep"
        for dep in $(grep -a -o 'depends=[-_a-z0-9,]*' "$f" | head -1 | sed 's/^depends=//' | tr ',' ' '); do
            add_mod "$dep"
        done
        order="$order $name"
    }
    for m in can-dev vcan can can-raw; do add_mod "$m"; done
    rm -rf "$CACHE/modules" && mkdir -p "$CACHE/modules"
    : >"$CACHE/modules.list.new"
    for m in $order; do
        f=$(echo "$mods" | grep -E "/${m//[-_]/[-_]}\.ko(\.xz|\.zst|\.gz)?$" | head -1)
        case "$f" in
            *.ko.xz) xz -dc "$f" >"$CACHE/modules/$m.ko" ;;
            *.ko.zst) zstd -qdc "$f" >"$CACHE/modules/$m.ko" ;;
            *.ko.gz) gzip -dc "$f" >"$CACHE/modules/$m.ko" ;;
            *) cp "$f" "$CACHE/modules/$m.ko" ;;
        esac
        echo "$m" >>"$CACHE/modules.list.new"
    done
    echo "$kver" >"$CACHE/kernel.version"
    mv "$CACHE/vmlinuz.new" "$CACHE/vmlinuz"
    mv "$CACHE/modules.list.new" "$CACHE/modules.list"
    rm -rf "$CACHE/x" "$CACHE/dl"
fi
say "kernel $(cat "$CACHE/kernel.version"), modules: $(tr '\n' ' ' <"$CACHE/modules.list")"

# 4. The initramfs: busybox, modules, can-utils, odo-replay-guest + libraries, test data.
R=$W/root
mkdir -p "$R"/{bin,sbin,lib/modules,proc,sys,dev,tmp,test,etc}
for applet in sh ash ip insmod mount sleep cat grep awk cmp diff wc tr head rm mkdir uname poweroff kill \
    echo date seq sync; do
    ln -sf busybox "$R/bin/$applet"
done
copy_with_libs() {
    local src=$1 dst=$2 lib
    cp "$src" "$R/bin/$dst"
    for lib in $(ldd "$src" 2>/dev/null | grep -o '/[^ ]*' || true); do
        mkdir -p "$R$(dirname "$lib")"
        cp -L "$lib" "$R$lib"
    done
}
copy_with_libs "$BUSYBOX" busybox  # busybox-static has no libraries; a dynamic one brings its own
copy_with_libs "$B/bin/odo-replay-guest" odo-replay
for t in candump canplayer cansend; do copy_with_libs "$(command -v $t)" "$t"; done
cp "$CACHE"/modules/*.ko "$R/lib/modules/"
cp "$CACHE/modules.list" "$R/lib/modules/"
cp "$W/data/"* "$R/test/"
cp "$S/tests/vcan/vcan_guest.sh" "$R/test/"
cat >"$R/init" <<'EOF'
#!/bin/sh
export PATH=/bin:/sbin
echo "vcan: init"
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev 2>/dev/null
mount -t tmpfs tmp /tmp
for m in $(cat /lib/modules/modules.list); do
    insmod /lib/modules/$m.ko || echo "ODO-VCAN-VERDICT: FAIL insmod $m"
done
ip link set lo up
D=/test REPLAY=/bin/odo-replay IF=vcan0 W=/tmp/work sh /test/vcan_guest.sh
echo "vcan: guest done"
sync
poweroff -f
EOF
chmod +x "$R/init"
(cd "$R" && find . | cpio -o -H newc --quiet | gzip -1) >"$W/initramfs.cpio.gz"

# 5. Boot: KVM if it works here, else (or if KVM fails to start) TCG.
QEMU_ARGS=(-m 384 -smp 1 -display none -no-reboot -serial "file:$W/console.txt" -monitor none -nic none
    -kernel "$CACHE/vmlinuz" -initrd "$W/initramfs.cpio.gz"
    -append "console=ttyS0 quiet loglevel=3 panic=-1 rdinit=/init")
TIMEOUT=${ODO_VCAN_TIMEOUT:-150}
run_guest() {
set +e
qrc=1
: >"$W/console.txt"
if [ -w /dev/kvm ] && [ "${ODO_VCAN_ACCEL:-auto}" != tcg ]; then
    # KVM can exist and still hang (nested virtualisation): give the guest 8 s to reach /init.
    say "trying KVM"
    : >"$W/console.txt"
    timeout "$TIMEOUT" qemu-system-x86_64 -accel kvm -cpu host "${QEMU_ARGS[@]}" </dev/null >/dev/null 2>&1 &
    qpid=$!
    for _ in $(seq 1 80); do
        grep -q "^vcan: init" "$W/console.txt" 2>/dev/null && break
        kill -0 "$qpid" 2>/dev/null || break
        sleep 0.1
    done
    if grep -q "^vcan: init" "$W/console.txt" 2>/dev/null; then
        wait "$qpid"
        qrc=$?
    else
        kill "$qpid" 2>/dev/null
        wait "$qpid" 2>/dev/null
        say "KVM did not start the guest here; falling back to TCG"
        ODO_VCAN_ACCEL=tcg
    fi
fi
if ! grep -q "ODO-VCAN-VERDICT" "$W/console.txt"; then
    say "booting under qemu with TCG"
    : >"$W/console.txt"
    timeout "$TIMEOUT" qemu-system-x86_64 -accel tcg "${QEMU_ARGS[@]}" </dev/null 2>"$W/qemu.err"
    qrc=$?
fi
set -e
}
run_guest
if tr -d '\r' <"$W/console.txt" | grep -q "^ODO-VCAN-VERDICT: FAIL-TIMING"; then
    tr -d '\r' <"$W/console.txt" | grep -E "^(vcan|ODO-VCAN)" || true
    say "the guest was too slow to keep the bus timing (above); running it once more"
    run_guest
fi
tr -d '\r' <"$W/console.txt" | grep -E "^(vcan|ODO-VCAN)" || true
T1=$(date +%s.%N)
verdict=$(tr -d '\r' <"$W/console.txt" | grep -m1 "^ODO-VCAN-VERDICT:" || true)
[ -n "$verdict" ] || { tail -30 "$W/console.txt"; die "no verdict on the serial console (qemu exit $qrc)"; }
say "$(awk -v a="$T0" -v b="$T1" 'BEGIN {printf "%.1f s in all", b - a}')"
case "$verdict" in
    "ODO-VCAN-VERDICT: PASS"*) exit 0 ;;
    *) die "$verdict" ;;
esac
