#!/usr/bin/env bash
# Installs what the hardware-in-the-loop harness needs on a Debian 12 host:
# QEMU >= 8.1 (virtio-multitouch-pci and QMP multi-touch events) from bookworm-backports,
# busybox-static for the guest, kmod (depmod), cpio, xz-utils, zstd, gcc and libc6-dev
# (static guest helpers), python3 (the host driver, stdlib only).
# Exit status: 0 ready, 77 cannot install here (reason on stderr), 1 failed.
set -euo pipefail

need_qemu() {
    command -v qemu-system-x86_64 >/dev/null 2>&1 &&
        qemu-system-x86_64 -device help 2>/dev/null | grep -q virtio-multitouch-pci
}
have_all() {
    need_qemu && [ -x /bin/busybox ] && command -v depmod >/dev/null && command -v cpio >/dev/null &&
        command -v xz >/dev/null && command -v zstd >/dev/null && command -v gcc >/dev/null &&
        command -v python3 >/dev/null && [ -e /usr/include/linux/uhid.h ]
}

if have_all; then
    exit 0
fi
if [ "$(id -u)" != 0 ]; then
    echo "hil: skipped: not root, and the packages are missing (qemu-system-x86 >= 8.1 from bookworm-backports, busybox-static, kmod, cpio, xz-utils, zstd, gcc, libc6-dev)" >&2
    exit 77
fi
if ! command -v apt-get >/dev/null 2>&1; then
    echo "hil: skipped: no apt-get on this machine; install QEMU >= 8.1, busybox-static, kmod, cpio, xz, zstd, gcc by hand" >&2
    exit 77
fi
codename="$(. /etc/os-release && echo "${VERSION_CODENAME:-}")"
if [ "$codename" = bookworm ] && ! grep -rqs bookworm-backports /etc/apt/sources.list /etc/apt/sources.list.d/; then
    # The mirror this machine already uses for bookworm.
    uri="$(grep -h '^URIs:' /etc/apt/sources.list.d/*.sources 2>/dev/null | awk '{print $2; exit}')"
    [ -n "$uri" ] || uri="$(awk '$1=="deb" && $3 ~ /^bookworm/ {print $2; exit}' /etc/apt/sources.list 2>/dev/null)"
    if [ -z "$uri" ]; then
        echo "hil: skipped: no Debian mirror in the apt sources to add bookworm-backports from" >&2
        exit 77
    fi
    printf 'Types: deb\nURIs: %s\nSuites: bookworm-backports\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' "$uri" \
        >/etc/apt/sources.list.d/crowdtouch-hil-backports.sources
fi
if ! apt-get update -q >/tmp/crowdtouch-hil-apt.log 2>&1; then
    echo "hil: skipped: apt-get update failed (no package mirror reachable); see /tmp/crowdtouch-hil-apt.log" >&2
    tail -n 5 /tmp/crowdtouch-hil-apt.log >&2
    exit 77
fi
qemu_suite=()
[ "$codename" = bookworm ] && qemu_suite=(-t bookworm-backports)
if ! apt-get install -y -q --no-install-recommends "${qemu_suite[@]}" qemu-system-x86 >>/tmp/crowdtouch-hil-apt.log 2>&1; then
    echo "hil: failed: could not install qemu-system-x86 ${qemu_suite[*]}; see /tmp/crowdtouch-hil-apt.log" >&2
    tail -n 5 /tmp/crowdtouch-hil-apt.log >&2
    exit 1
fi
if ! apt-get install -y -q --no-install-recommends busybox-static kmod cpio xz-utils zstd gcc libc6-dev linux-libc-dev python3 >>/tmp/crowdtouch-hil-apt.log 2>&1; then
    echo "hil: failed: could not install busybox-static kmod cpio xz-utils zstd gcc libc6-dev; see /tmp/crowdtouch-hil-apt.log" >&2
    tail -n 5 /tmp/crowdtouch-hil-apt.log >&2
    exit 1
fi
if ! need_qemu; then
    echo "hil: failed: $(qemu-system-x86_64 --version | head -1) has no virtio-multitouch-pci (QEMU >= 8.1 needed)" >&2
    exit 1
fi
echo "hil: $(qemu-system-x86_64 --version | head -1)"
