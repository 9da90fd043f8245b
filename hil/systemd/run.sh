#!/usr/bin/env bash
# The system test on a real systemd: boots Debian 12 (a root filesystem built by
# mmdebstrap from Debian's packages, cached under target/systemd-guest/) in QEMU,
# installs the crowdtouch package with apt and checks the service as a kiosk meets
# it (hil/systemd/guest/systest.py lists the checks; hil/README.md describes them).
#
#   hil/systemd/run.sh [--deb FILE.deb] [--accel tcg|kvm]
#
# Without --deb the package is built by packaging/deb.sh (from the HIL's static
# release daemon when target/hil has one, else a release build).
# Exit status: 0 every check passed, 1 a step or a check failed, 77 skipped because
# this machine cannot run it (the reason is printed). No QEMU outlives the script.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
cd "$ROOT"
DIR="${SYSTEST_DIR:-$ROOT/target/systemd-guest}"
SUITE=bookworm
# What the guest has besides the apt variant; a change here, in BASE_VERSION or in
# guest/systest.service makes a new cached root.
BASE_VERSION=1
PACKAGES="systemd,systemd-sysv,udev,dbus,linux-image-amd64,initramfs-tools,python3,iproute2,kmod,procps"
deb=""
accel=tcg
while [ $# -gt 0 ]; do
    case "$1" in
        --deb) deb="$2"; shift 2 ;;
        --accel) accel="$2"; shift 2 ;;
        *) echo "usage: hil/systemd/run.sh [--deb FILE.deb] [--accel tcg|kvm]" >&2; exit 2 ;;
    esac
done
t0=$(date +%s)
step() { printf 'systemd-test: %s (%ds)\n' "$*" "$(($(date +%s) - t0))"; }
fail() { echo "systemd-test: failed: $*" >&2; exit 1; }
mkdir -p "$DIR"
# host.py stops its QEMU itself; should it be killed, the guest's pid file says
# which process to end (that one only).
stop_guest() {
    local p
    p="$(cat "$DIR/run/qemu.pid" 2>/dev/null || true)"
    if [ -n "$p" ]; then kill -KILL "$p" 2>/dev/null || true; fi
}
trap stop_guest EXIT

step "dependencies"
case "$(uname -m)" in x86_64) ;; *) echo "systemd-test: skipped: the guest is x86_64, this host is $(uname -m)"; exit 77 ;; esac
rc=0
"$ROOT/hil/deps.sh" || rc=$?
if [ "$rc" = 77 ]; then exit 77; elif [ "$rc" != 0 ]; then exit 1; fi
if ! command -v mmdebstrap >/dev/null || ! command -v mke2fs >/dev/null || ! command -v qemu-img >/dev/null; then
    if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null; then
        echo "systemd-test: skipped: mmdebstrap, e2fsprogs or qemu-utils missing, and not root with apt to install them"
        exit 77
    fi
    apt-get install -y -q --no-install-recommends mmdebstrap e2fsprogs qemu-utils >"$DIR/apt.log" 2>&1 ||
        fail "could not install mmdebstrap e2fsprogs qemu-utils (see $DIR/apt.log)"
fi
if [ "$(id -u)" != 0 ]; then
    echo "systemd-test: skipped: building the guest's root filesystem needs root (mmdebstrap, file ownership)"
    exit 77
fi

step "the package"
if [ -z "$deb" ]; then
    triple="$(rustc -vV | awk '/^host:/{print $2}')"
    static="$ROOT/target/hil/$triple/hil/crowdtouch"
    if [ -x "$static" ]; then
        deb="$("$ROOT/packaging/deb.sh" --binary "$static" | tail -n 1)" || fail "packaging/deb.sh"
    else
        deb="$("$ROOT/packaging/deb.sh" | tail -n 1)" || fail "packaging/deb.sh"
    fi
fi
[ -f "$deb" ] || fail "no package at $deb"

step "root filesystem (mmdebstrap $SUITE, cached)"
key="$(printf '%s %s %s %s' "$SUITE" "$PACKAGES" "$BASE_VERSION" "$(sha256sum <"$HERE/guest/systest.service")" | sha256sum | cut -c1-16)"
base="$DIR/base-$key"
if [ ! -f "$base/done" ]; then
    rm -rf "$DIR"/base-* && mkdir -p "$base"
    mirror="$(grep -h '^URIs:' /etc/apt/sources.list.d/*.sources 2>/dev/null | awk '{print $2; exit}')"
    [ -n "$mirror" ] || mirror="$(awk '$1=="deb" {print $2; exit}' /etc/apt/sources.list 2>/dev/null)"
    [ -n "$mirror" ] || mirror=http://deb.debian.org/debian
    if ! mmdebstrap --variant=apt --include="$PACKAGES" "$SUITE" "$base/rootfs.tar" "$mirror" \
            >"$base/mmdebstrap.log" 2>&1; then
        tail -n 5 "$base/mmdebstrap.log" >&2
        if grep -qiE 'could not resolve|failed to fetch|unable to connect|temporary failure' "$base/mmdebstrap.log"; then
            echo "systemd-test: skipped: Debian's package mirror $mirror cannot be reached"
            exit 77
        fi
        fail "mmdebstrap (see $base/mmdebstrap.log)"
    fi
    r="$base/root"
    mkdir -p "$r"
    tar --numeric-owner -xf "$base/rootfs.tar" -C "$r"
    cp "$(ls "$r"/boot/vmlinuz-* | head -n 1)" "$base/vmlinuz"
    cp "$(ls "$r"/boot/initrd.img-* | head -n 1)" "$base/initrd.img"
    # The guest: the root on the first virtio disk, the test's files on the second;
    # DHCP on QEMU's user network; the test as a unit at boot; nothing slow.
    printf '/dev/vda / ext4 rw,errors=remount-ro 0 1\n/dev/vdb /opt/systest ext4 rw 0 2\n' >"$r/etc/fstab"
    mkdir -p "$r/opt/systest"
    echo kiosk >"$r/etc/hostname"
    printf '[Match]\nName=en* eth*\n\n[Network]\nDHCP=yes\n' >"$r/etc/systemd/network/20-wired.network"
    ln -sf /lib/systemd/system/systemd-networkd.service "$r/etc/systemd/system/multi-user.target.wants/systemd-networkd.service"
    mkdir -p "$r/etc/systemd/system/sockets.target.wants"
    ln -sf /lib/systemd/system/systemd-networkd.socket "$r/etc/systemd/system/sockets.target.wants/systemd-networkd.socket"
    cp "$HERE/guest/systest.service" "$r/etc/systemd/system/systest.service"
    ln -sf /etc/systemd/system/systest.service "$r/etc/systemd/system/multi-user.target.wants/systest.service"
    for u in apt-daily.timer apt-daily-upgrade.timer e2scrub_all.timer e2scrub_reap.service fstrim.timer; do
        ln -sf /dev/null "$r/etc/systemd/system/$u"
    done
    mke2fs -q -t ext4 -L root -d "$r" "$base/root.img" 3G || fail "mke2fs of the root filesystem"
    rm -rf "$r" "$base/rootfs.tar"
    touch "$base/done"
    step "root filesystem built: $(du -h "$base/root.img" | cut -f1) used of 3G"
fi

step "the test's disk (package, scripts, uhid bridge)"
run="$DIR/run"
rm -rf "$run" && mkdir -p "$run/payload"
cp "$deb" "$run/payload/crowdtouch.deb"
cp "$HERE"/guest/* "$run/payload/"
cp "$ROOT/hil/hidgen.py" "$run/payload/"
cp "$ROOT/tests/fixtures/hid/descriptors/3m_0596_0500.rdesc" "$run/payload/touch.rdesc"
gcc -static -O2 -Wall -o "$run/payload/uhidbridge" "$ROOT/hil/guest/uhidbridge.c" || fail "building uhidbridge"
mke2fs -q -t ext4 -d "$run/payload" "$run/payload.img" 256M || fail "mke2fs of the test's disk"
# The cached root stays as built: the guest writes to an overlay.
qemu-img create -q -f qcow2 -F raw -b "$base/root.img" "$run/root.qcow2" || fail "qemu-img overlay"

step "boot and test (QEMU $accel)"
rc=0
python3 "$HERE/host.py" --kernel "$base/vmlinuz" --initrd "$base/initrd.img" --root "$run/root.qcow2" \
    --payload "$run/payload.img" --out "$run" --accel "$accel" || rc=$?
step "done (results in $run/results.json, guest console in $run/console.log)"
exit $rc
