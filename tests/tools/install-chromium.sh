#!/bin/sh
# Installs Debian's `chromium` for the real-browser test of the live viewer
# (tests/viewer_browser.rs). Playwright's and Puppeteer's own browser downloads do
# not work here; the distribution's package does.
#
# Exit codes: 0 chromium is at /usr/bin/chromium (already, or installed now);
# 2 it cannot be installed here (not root, no apt-get, no network): the reason is
# printed on stderr, and the caller skips the browser test saying so.
set -u

CHROMIUM=/usr/bin/chromium

if [ -x "$CHROMIUM" ]; then
    echo "chromium: $("$CHROMIUM" --version 2>/dev/null || echo present) at $CHROMIUM"
    exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
    echo "cannot install chromium: no apt-get on this machine" >&2
    exit 2
fi
if [ "$(id -u)" != 0 ]; then
    echo "cannot install chromium: apt-get needs root (uid $(id -u)); run: sudo apt-get install -y chromium" >&2
    exit 2
fi
export DEBIAN_FRONTEND=noninteractive
# Another apt-get (another test binary, the machine's own updates) may hold dpkg's
# lock: wait for it rather than fail.
APT="apt-get -o DPkg::Lock::Timeout=600"
# The package lists may be missing (a fresh container) or stale.
if ! $APT install -y --no-install-recommends chromium >/tmp/install-chromium.log 2>&1; then
    $APT update >>/tmp/install-chromium.log 2>&1 || true
    if ! $APT install -y --no-install-recommends chromium >>/tmp/install-chromium.log 2>&1; then
        echo "cannot install chromium: apt-get install failed (no network?); see /tmp/install-chromium.log:" >&2
        tail -n 5 /tmp/install-chromium.log >&2
        exit 2
    fi
fi
if [ ! -x "$CHROMIUM" ]; then
    echo "cannot install chromium: installed, but $CHROMIUM is missing" >&2
    exit 2
fi
echo "chromium: $("$CHROMIUM" --version 2>/dev/null) installed at $CHROMIUM"
