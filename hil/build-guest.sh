#!/usr/bin/env bash
# Builds the hardware-in-the-loop guest: a Debian kernel (downloaded with apt, unpacked,
# never installed), the input/HID modules it needs, and a busybox initramfs holding the
# statically linked daemon and the guest helpers (uhid bridge, socket forwarder).
#
#   hil/build-guest.sh DAEMON_BINARY
#
# Everything goes to $HIL_DIR (default target/hil-guest). Cached between runs:
#   kernel/<version>/{vmlinux,modules/...}   keyed by the kernel package version
#   initrd-<kernel version>-<hash>.cpio.gz  keyed by the daemon's and the guest files' hash
# Prints the paths as `KERNEL=...` and `INITRD=...` on its last two lines.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
ROOT="$(cd "$HERE/.." && pwd)"
HIL_DIR="${HIL_DIR:-$ROOT/target/hil-guest}"
daemon="${1:?usage: build-guest.sh DAEMON_BINARY}"
fail() { echo "hil: build-guest: $*" >&2; exit 1; }
[ -x "$daemon" ] || fail "daemon binary $daemon is missing or not executable"

# The pinned guest kernel: the Debian 12 package the harness was written against. When
# the mirror has dropped it (Debian removes superseded ABIs), the current one is used
# and said so.
PINNED_KPKG="linux-image-6.1.0-56-amd64"
KPKG="${HIL_KPKG:-$PINNED_KPKG}"
mkdir -p "$HIL_DIR/dl" && cd "$HIL_DIR/dl"
if ! ls "${KPKG}"_*.deb >/dev/null 2>&1; then
    if ! apt-get download "$KPKG" >/dev/null 2>"$HIL_DIR/dl/apt.err"; then
        alt="$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-/{print $2; exit}')"
        [ -n "$alt" ] || fail "cannot download $KPKG ($(tail -n 1 "$HIL_DIR/dl/apt.err")) and apt knows no linux-image-amd64"
        echo "hil: $KPKG is no longer on the mirror; using $alt" >&2
        KPKG="$alt"
        ls "${KPKG}"_*.deb >/dev/null 2>&1 || apt-get download "$KPKG" >/dev/null 2>"$HIL_DIR/dl/apt.err" ||
            fail "cannot download $KPKG: $(tail -n 1 "$HIL_DIR/dl/apt.err")"
    fi
fi
deb="$(ls "${KPKG}"_*.deb | head -n 1)"

# 1. The kernel, unpacked once per package version.
kver_of_deb() { dpkg-deb -f "$1" Version; }
kdir="$HIL_DIR/kernel/$KPKG-$(kver_of_deb "$deb")"
if [ ! -f "$kdir/done" ]; then
    rm -rf "$kdir" && mkdir -p "$kdir"
    tmp="$(mktemp -d "$HIL_DIR/kroot.XXXXXX")"
    trap 'rm -rf "$tmp"' EXIT
    dpkg -x "$deb" "$tmp" || fail "cannot unpack $deb"
    kv="$(ls "$tmp/lib/modules")"
    depmod -b "$tmp" "$kv" || fail "depmod failed for $kv"
    # The uncompressed ELF vmlinux boots through its PVH entry point, skipping the
    # bzImage decompression that costs seconds under software emulation.
    python3 - "$tmp/boot/vmlinuz-$kv" "$kdir/vmlinux" <<'PY' || fail "cannot extract vmlinux from vmlinuz-$kv"
import lzma, subprocess, sys
d = open(sys.argv[1], "rb").read()
xz, zst = d.find(b"\xfd7zXZ\x00"), d.find(b"\x28\xb5\x2f\xfd")
if xz > 0:
    out = lzma.LZMADecompressor(format=lzma.FORMAT_XZ).decompress(d[xz:])
elif zst > 0:
    out = subprocess.run(["zstd", "-dc"], input=d[zst:], capture_output=True).stdout
else:
    sys.exit("unknown bzImage compression")
if out[:4] != b"\x7fELF":
    sys.exit("decompressed payload is not an ELF vmlinux")
open(sys.argv[2], "wb").write(out)
PY
    cfg="$tmp/boot/config-$kv"
    for opt in CONFIG_PVH CONFIG_DEVTMPFS CONFIG_HIDRAW; do
        grep -q "^$opt=y" "$cfg" || fail "kernel $kv lacks $opt=y"
    done
    # The module closure, in dependency order (modules.dep), decompressed for busybox insmod.
    md="$tmp/lib/modules/$kv"
    declare -A seen=()
    order=()
    add() {
        local p="$1"
        [ -n "${seen[$p]:-}" ] && return
        seen[$p]=1
        local d
        for d in $(grep -E "^$p:" "$md/modules.dep" | cut -d: -f2); do add "$d"; done
        order+=("$p")
    }
    for m in virtio_pci virtio_input evdev usbhid hid_generic hid_multitouch uhid; do
        p="$(grep -E "/(${m}|${m//_/-})\.ko(\.xz|\.zst|\.gz)?:" "$md/modules.dep" | cut -d: -f1 | head -n 1 || true)"
        if [ -z "$p" ]; then
            grep -qE "/(${m}|${m//_/-})\.ko$" "$md/modules.builtin" && continue
            fail "kernel $kv has no module $m (needed for the touch devices)"
        fi
        add "$p"
    done
    mkdir -p "$kdir/modules"
    : >"$kdir/modules.order"
    for p in "${order[@]}"; do
        q="${p%.xz}"; q="${q%.zst}"; q="${q%.gz}"
        mkdir -p "$kdir/modules/$(dirname "$q")"
        case "$p" in
            *.xz) xz -dc "$md/$p" >"$kdir/modules/$q" ;;
            *.zst) zstd -qdc "$md/$p" >"$kdir/modules/$q" ;;
            *.gz) gzip -dc "$md/$p" >"$kdir/modules/$q" ;;
            *) cp "$md/$p" "$kdir/modules/$q" ;;
        esac
        echo "$q" >>"$kdir/modules.order"
    done
    echo "$kv" >"$kdir/kernel.release"
    grep -E '^CONFIG_UEVENT_HELPER=' "$cfg" >"$kdir/uevent_helper" || true
    rm -rf "$tmp"
    trap - EXIT
    touch "$kdir/done"
    echo "hil: kernel $kv unpacked ($(wc -l <"$kdir/modules.order") modules)" >&2
fi
kv="$(cat "$kdir/kernel.release")"

# 2. The initramfs, once per daemon binary and guest file set.
hash="$(cat "$daemon" "$HERE"/guest/* "$0" | sha256sum | cut -c1-16)"
initrd="$HIL_DIR/initrd-$kv-$hash.cpio.gz"
if [ ! -f "$initrd" ]; then
    r="$(mktemp -d "$HIL_DIR/initramfs.XXXXXX")"
    trap 'rm -rf "$r"' EXIT
    chmod 0755 "$r"
    mkdir -p "$r"/{bin,etc,proc,sys,dev,tmp,run,lib/modules/"$kv"}
    cp /bin/busybox "$r/bin/busybox"
    (cd "$r/bin" && for a in $(./busybox --list); do [ "$a" = busybox ] || ln -s busybox "$a"; done)
    gcc -static -O2 -Wall -o "$r/bin/uhidbridge" "$HERE/guest/uhidbridge.c" || fail "cannot build uhidbridge"
    gcc -static -O2 -Wall -o "$r/bin/sockfwd" "$HERE/guest/sockfwd.c" || fail "cannot build sockfwd"
    gcc -static -O2 -Wall -o "$r/bin/runas" "$HERE/guest/runas.c" || fail "cannot build runas"
    cp "$daemon" "$r/bin/crowdtouch"
    cp "$HERE/guest/init" "$r/init"
    gcc -static -O2 -Wall -o "$r/bin/hil-udevd" "$HERE/guest/hil-udevd.c" || fail "cannot build hil-udevd"
    cp "$HERE/guest/hil-ctl" "$r/bin/"
    chmod +x "$r/init" "$r/bin/hil-ctl"
    cp -r "$kdir/modules/." "$r/lib/modules/$kv/"
    cp "$kdir/modules.order" "$r/etc/modules.order"
    printf 'root:x:0:0:root:/:/bin/sh\ncrowdtouch:x:900:900:crowdtouch:/:/bin/false\n' >"$r/etc/passwd"
    printf 'root:x:0:\ncrowdtouch:x:900:\n' >"$r/etc/group"
    (cd "$r" && find . | cpio -o -H newc --quiet | gzip -1 >"$initrd.tmp") || fail "cannot pack the initramfs"
    mv "$initrd.tmp" "$initrd"
    rm -rf "$r"
    trap - EXIT
    echo "hil: initramfs $(basename "$initrd") ($(du -h "$initrd" | cut -f1))" >&2
fi
echo "KERNEL=$kdir/vmlinux"
echo "INITRD=$initrd"
