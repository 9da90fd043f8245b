#!/usr/bin/env bash
# Builds the Debian package into target/debian/crowdtouch_<version>_<arch>.deb,
# installing its own tools first (cargo-deb from crates.io; lintian and dpkg-dev
# from Debian's packages when this is a Debian machine and we are root), then
# checks it with lintian.
#
#   packaging/deb.sh                  # build and lint; prints the .deb's path last
#   packaging/deb.sh --no-lint        # build only
#   packaging/deb.sh --binary PATH    # package this release build of the daemon
#                                     # (CI: the HIL's static one) instead of building
#
# Exit status: 0 built (and lintian clean but for the tags packaging/lintian-expected
# explains), 1 failed.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
cd "$ROOT"
CARGO_DEB_VERSION=3.8.0
lint=1
binary=""
while [ $# -gt 0 ]; do
    case "$1" in
        --no-lint) lint=0; shift ;;
        --binary) binary="$2"; shift 2 ;;
        *) echo "usage: packaging/deb.sh [--no-lint] [--binary PATH]" >&2; exit 2 ;;
    esac
done
say() { printf 'deb: %s\n' "$*" >&2; }

# 1. The tools.
if ! cargo deb --version 2>/dev/null | grep -q "$CARGO_DEB_VERSION"; then
    say "installing cargo-deb $CARGO_DEB_VERSION (cargo install, a few minutes once)"
    cargo install --locked --quiet cargo-deb --version "$CARGO_DEB_VERSION"
fi
if [ "$lint" = 1 ] && ! command -v lintian >/dev/null 2>&1; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        say "installing lintian"
        apt-get install -y -q --no-install-recommends lintian >/tmp/crowdtouch-deb-apt.log 2>&1 ||
            { apt-get update -q >>/tmp/crowdtouch-deb-apt.log 2>&1 &&
              apt-get install -y -q --no-install-recommends lintian >>/tmp/crowdtouch-deb-apt.log 2>&1; } ||
            { say "failed: could not install lintian (see /tmp/crowdtouch-deb-apt.log)"; exit 1; }
    else
        say "lintian is not installed and cannot be installed here (not root, or no apt): not linted"
        lint=0
    fi
fi

# 2. The binary and the man pages (generated from the command line's definitions).
mkdir -p target/deb-bin
if [ -z "$binary" ]; then
    say "cargo build --release"
    cargo build --release --quiet --bin crowdtouch
    binary=target/release/crowdtouch
fi
cp "$binary" target/deb-bin/crowdtouch
# Debug symbols stay in the build (profile.release keeps them for backtraces).
strip --strip-unneeded target/deb-bin/crowdtouch
rm -rf target/man && mkdir -p target/man
target/deb-bin/crowdtouch man target/man
gzip -9n target/man/*.1
rm -rf target/debian-doc && mkdir -p target/debian-doc
gzip -9nc packaging/debian/changelog >target/debian-doc/changelog.gz

# 3. The package. cargo-deb names it NAME_VERSION-REVISION_ARCH; the scripts that
# use it expect NAME_VERSION_ARCH (a native package: no Debian revision).
version="$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print([p for p in json.load(sys.stdin)["packages"] if p["name"]=="crowdtouch"][0]["version"])')"
arch="$(dpkg --print-architecture 2>/dev/null || echo amd64)"
out="target/debian/crowdtouch_${version}_${arch}.deb"
mkdir -p target/debian
say "cargo deb"
cargo deb --no-build --no-strip --deb-version "$version" --output "$out" >&2
[ -f "$out" ] || { say "failed: cargo deb wrote no $out"; exit 1; }

# 4. lintian: every tag it reports must be one packaging/lintian-expected explains.
if [ "$lint" = 1 ]; then
    say "lintian"
    tags="$(lintian --no-tag-display-limit "$out" 2>&1 || true)"
    unexplained="$( (printf '%s\n' "$tags" | grep -E '^[EWIP]: ' || true) | while read -r line; do
        tag="$(awk '{print $3}' <<<"$line")"
        grep -q "^$tag " packaging/lintian-expected || printf '%s\n' "$line"
    done)"
    printf '%s\n' "$tags" | grep -E '^[EW]: ' >&2 || true
    if [ -n "$unexplained" ]; then
        say "failed: lintian tags not explained in packaging/lintian-expected:"
        printf '%s\n' "$unexplained" >&2
        exit 1
    fi
    say "lintian: no unexplained tag"
fi
echo "$ROOT/$out"
