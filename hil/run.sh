#!/usr/bin/env bash
# Hardware-in-the-loop: builds the statically linked daemon, the guest kernel and
# initramfs (cached), boots QEMU guests and runs every scenario (hil/hil.py).
#
#   hil/run.sh [hil.py options: --only evdev,hidraw --accel kvm --cpu host --json F]
#
# Exit status: 0 all scenarios passed, 1 a step or scenario failed, 77 skipped because
# this machine cannot run it (the reason is printed). Nothing is left running.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
ROOT="$(cd "$HERE/.." && pwd)"
cd "$ROOT"
export HIL_DIR="${HIL_DIR:-$ROOT/target/hil-guest}"
mkdir -p "$HIL_DIR"
t0=$(date +%s)
step() { printf 'hil: %s (%ds)\n' "$*" "$(($(date +%s) - t0))"; }
# Whatever happens to the driver, no guest outlives this script.
trap 'pkill -KILL -f "qemu-system-x86_64.*$HIL_DIR/run/" 2>/dev/null || true' EXIT

build_daemon() {
    triple="$(rustc -vV | awk '/^host:/{print $2}')"
    case "$triple" in
        x86_64-unknown-linux-gnu) ;;
        *) echo "hil: skipped: the guest is x86_64 and this host builds for $triple"; exit 77 ;;
    esac
    # A concurrent `--build-only` run holds cargo's lock on target/hil; this waits for it.
    if ! RUSTFLAGS="-C target-feature=+crt-static" cargo build --quiet --profile hil \
            --target "$triple" --target-dir "$ROOT/target/hil" --bin crowdtouch; then
        echo "hil: failed: the static daemon did not build" >&2
        exit 1
    fi
    daemon="$ROOT/target/hil/$triple/hil/crowdtouch"
}

# `--build-only`: just the static daemon (CI starts this early, in the background).
if [ "${1:-}" = --build-only ]; then
    step "statically linked daemon (cargo --profile hil, +crt-static)"
    build_daemon
    step "built $daemon"
    exit 0
fi

step "dependencies"
rc=0
"$HERE/deps.sh" || rc=$?
if [ "$rc" = 77 ]; then exit 77; elif [ "$rc" != 0 ]; then exit 1; fi

step "statically linked daemon (cargo --profile hil, +crt-static)"
build_daemon

step "guest kernel and initramfs"
out="$("$HERE/build-guest.sh" "$daemon")" || { echo "hil: failed: building the guest" >&2; exit 1; }
kernel="$(sed -n 's/^KERNEL=//p' <<<"$out")"
initrd="$(sed -n 's/^INITRD=//p' <<<"$out")"

step "scenarios"
rc=0
python3 "$HERE/hil.py" --kernel "$kernel" --initrd "$initrd" --json "$HIL_DIR/results.json" "$@" || rc=$?
step "done (results in $HIL_DIR/results.json, logs in $HIL_DIR/run/)"
exit $rc
