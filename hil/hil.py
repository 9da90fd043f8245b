#!/usr/bin/env python3
"""crowdtouch hardware-in-the-loop: the real daemon, in `run` mode, reading a real Linux
kernel's evdev and hidraw nodes inside a QEMU guest, driven from the host with known
touches; its socket stream comes back over a serial port and is checked.

  hil.py --kernel VMLINUX --initrd INITRD [--accel tcg|kvm] [--cpu host]
         [--only NAME[,NAME]] [--json FILE] [--workdir DIR] [--udev-rule FILE]

Scenarios (each a group of checks; a failed check fails the run):
  evdev-N        virtio-multitouch, N = 1, 2, 3, 5 fingers: down on the crowd, drag,
                 staggered lift; the control kind, the touches and the crowd's move
  evdev-hotplug  the device removed mid-gesture (QMP device_del) and added back
  evdev-overload the daemon starved (SIGSTOP) until the kernel reports SYN_DROPPED,
                 a finger lifted and another put down meanwhile; resync
  evdev-permissions  node left root 0600 (the udev rule not applied): the documented
                 error, then the daemon attaches once the rule's group and mode are set
  hidraw-<dev>   uhid with a real report descriptor from tests/fixtures/hid; reports
                 generated from the descriptor (hidgen.py); the daemon's hidapi reader
  hidraw-hotplug the uhid device destroyed mid-gesture and created again

Latency, per scenario: host send -> snapshot line back on the host (total); guest
kernel timestamp -> the guest client's read (the daemon's part, measured in the guest
on CLOCK_MONOTONIC); total minus the daemon's part (QEMU's transport both ways).

Stdlib only. Every QEMU started is killed when the run ends, however it ends.
"""
import argparse
import atexit
import gzip
import json
import math
import os
import re
import signal
import socket
import statistics
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import hidgen  # noqa: E402

WORLD = (16.0, 9.0)          # the world rectangle the config maps the surface onto (m)
FORMATION_CENTRE = (7.7, 4.4)  # on the crowd, off the surface centre (where swapped axes agree)
VIRTIO_MAX = 32767           # virtio-multitouch axis range 0..32767
DAEMON_UID = 900             # the crowdtouch user in the guest's /etc/passwd
SNAPSHOT_TIMEOUT_S = 3.0

_guests = []


class StepError(Exception):
    """A step of the harness failed; the message says which and why."""


def _kill_all():
    for g in list(_guests):
        g.kill()


atexit.register(_kill_all)
for _sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
    signal.signal(_sig, lambda s, f: (_kill_all(), sys.exit(128 + s)))


# ------------------------------------------------------------------ guest plumbing
def cpio_newc(files):
    """A newc cpio archive of {path: bytes} (directories created as needed)."""
    out = bytearray()
    ino = 1000
    dirs = set()
    entries = []
    for path in sorted(files):
        parts = path.split("/")[:-1]
        for k in range(1, len(parts) + 1):
            d = "/".join(parts[:k])
            if d not in dirs:
                dirs.add(d)
                entries.append((d, None))
        entries.append((path, files[path]))

    def put(name, data, mode):
        nonlocal ino
        ino += 1
        nb = name.encode() + b"\0"
        hdr = "070701" + "".join(f"{v:08x}" for v in (
            ino, mode, 0, 0, 1, 0, len(data), 0, 0, 0, 0, len(nb), 0))
        out.extend(hdr.encode() + nb)
        out.extend(b"\0" * (-len(out) % 4))
        out.extend(data)
        out.extend(b"\0" * (-len(out) % 4))

    for name, data in entries:
        put(name, b"" if data is None else data, 0o040755 if data is None else 0o100644)
    put("TRAILER!!!", b"", 0)
    return bytes(out)


class QMP:
    def __init__(self, path, timeout=30.0):
        deadline = time.monotonic() + timeout
        while True:
            try:
                self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                self.sock.connect(path)
                break
            except (FileNotFoundError, ConnectionRefusedError):
                self.sock.close()
                if time.monotonic() > deadline:
                    raise StepError(f"QEMU's QMP socket {path} did not appear within {timeout} s")
                time.sleep(0.02)
        self.f = self.sock.makefile("rwb", buffering=0)
        self._read()
        self.cmd("qmp_capabilities")

    def _read(self):
        line = self.f.readline()
        if not line:
            raise StepError("QEMU closed its QMP socket (did it exit?)")
        return json.loads(line)

    def cmd(self, execute, **arguments):
        msg = {"execute": execute}
        if arguments:
            msg["arguments"] = arguments
        # compact JSON: QEMU's monitor reads about 4 us per byte under TCG
        self.f.write(json.dumps(msg, separators=(",", ":")).encode() + b"\n")
        while True:
            r = self._read()
            if "event" in r:
                continue
            if "error" in r:
                raise StepError(f"QMP {execute} failed: {r['error'].get('desc', r['error'])}")
            return r.get("return")


class Lines:
    """Lines from one source, each stamped with the host's monotonic clock on arrival."""

    def __init__(self, name, log_path):
        self.name = name
        self.items = []
        self.cv = threading.Condition()
        self.closed = False
        self.log = open(log_path, "w", buffering=1)

    def add(self, item, text):
        with self.cv:
            self.items.append(item)
            self.cv.notify_all()
        self.log.write(f"{item[0]} {text}\n")

    def close(self):
        with self.cv:
            self.closed = True
            self.cv.notify_all()

    def mark(self):
        with self.cv:
            return len(self.items)

    def wait(self, pred, start=0, timeout=10.0, what="a line"):
        deadline = time.monotonic() + timeout
        i = start
        with self.cv:
            while True:
                while i < len(self.items):
                    if pred(self.items[i]):
                        return i
                    i += 1
                if self.closed:
                    raise StepError(f"{self.name} closed while waiting for {what}")
                left = deadline - time.monotonic()
                if left <= 0:
                    raise StepError(f"timed out after {timeout:.1f} s waiting for {what} on {self.name}")
                self.cv.wait(left)

    def since(self, start):
        with self.cv:
            return list(self.items[start:])


class Guest:
    """One QEMU guest running the daemon, with its four serial lines."""

    def __init__(self, name, args, config_ron, devices, hellos, env_extra=None):
        self.name = name
        self.args = args
        self.dir = os.path.join(args.workdir, name)
        os.makedirs(self.dir, exist_ok=True)
        self.proc = None
        ev_gid, ev_mode, hid_gid, hid_mode = args.rule
        env = {"EV_GID": ev_gid, "EV_MODE": ev_mode, "HID_GID": hid_gid, "HID_MODE": hid_mode,
               "DAEMON_UID": DAEMON_UID, "DAEMON_GID": DAEMON_UID, "DAEMON_LOG": "info"}
        env.update(env_extra or {})
        run = cpio_newc({
            "etc/hil/run.env": "".join(f"{k}={v}\n" for k, v in env.items()).encode(),
            "etc/hil/crowdtouch.ron": config_ron.encode(),
            "etc/hil/hello0": hellos[0].encode(),
            "etc/hil/hello1": hellos[1].encode(),
        })
        self.initrd = os.path.join(self.dir, "initrd.cpio.gz")
        with open(args.initrd, "rb") as f, open(self.initrd, "wb") as o:
            o.write(f.read())
            o.write(gzip.compress(run, 1))  # the kernel unpacks concatenated archives
        self.sock = {k: os.path.join(self.dir, f"{k}.sock") for k in ("qmp", "uhid", "ctl", "stream")}
        for p in self.sock.values():
            if os.path.exists(p):
                os.unlink(p)
        cmd = ["qemu-system-x86_64", "-accel", args.accel, "-machine", "q35", "-m", "512",
               "-smp", "1", "-nodefaults", "-display", "none", "-no-reboot",
               "-kernel", args.kernel, "-initrd", self.initrd,
               "-append", "console=ttyS0 quiet panic=-1",
               "-qmp", f"unix:{self.sock['qmp']},server=on,wait=off",
               "-serial", "stdio",
               "-serial", f"unix:{self.sock['uhid']},server=on,wait=off",
               "-serial", f"unix:{self.sock['ctl']},server=on,wait=off",
               "-serial", f"unix:{self.sock['stream']},server=on,wait=off",
               "-device", "pcie-root-port,id=rp1,chassis=1,slot=1",
               *devices]
        if args.cpu:
            cmd[3:3] = ["-cpu", args.cpu]
        with open(os.path.join(self.dir, "qemu.cmd"), "w") as f:
            f.write(" ".join(cmd) + "\n")
        self.t0 = time.monotonic_ns()
        try:
            self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                         stderr=subprocess.STDOUT, start_new_session=True)
        except FileNotFoundError:
            raise StepError("qemu-system-x86_64 is not installed (run hil/deps.sh)")
        _guests.append(self)
        self.console = Lines(f"{name} console", os.path.join(self.dir, "console.log"))
        self.stream = Lines(f"{name} socket stream", os.path.join(self.dir, "stream.log"))
        threading.Thread(target=self._read_console, daemon=True).start()
        self.qmp = QMP(self.sock["qmp"])
        self.links = {}
        for k in ("uhid", "ctl", "stream"):
            s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            s.connect(self.sock[k])
            self.links[k] = s
        threading.Thread(target=self._read_stream, daemon=True).start()
        self.ctl_n = 0

    def _read_console(self):
        for raw in iter(self.proc.stdout.readline, b""):
            now = time.monotonic_ns()
            text = raw.decode(errors="replace").rstrip("\r\n")
            self.console.add((now, text), text)
        self.console.close()

    def _read_stream(self):
        f = self.links["stream"].makefile("rb")
        for raw in f:
            now = time.monotonic_ns()
            text = raw.decode(errors="replace").rstrip("\r\n")
            m = re.match(r"S(\d) (\d+) (.*)$", text)
            if m:
                try:
                    obj = json.loads(m.group(3))
                except ValueError:
                    obj = {"type": "<bad json>", "text": m.group(3)[:200]}
                self.stream.add((now, int(m.group(1)), int(m.group(2)), obj), text)
            else:
                self.stream.add((now, -1, 0, {"type": "<forwarder>", "text": text}), text)
        self.stream.close()

    def wait_ready(self, timeout=90.0):
        i = self.console.wait(lambda it: it[1].startswith(("HIL READY", "HIL ERR")), 0, timeout,
                              "the guest to boot (HIL READY)")
        line = self.console.items[i][1]
        if line.startswith("HIL ERR"):
            raise StepError(f"guest boot failed: {line[8:]}")
        self.boot_s = (self.console.items[i][0] - self.t0) / 1e9
        return line

    def ctl(self, command, timeout=10.0):
        self.ctl_n += 1
        n = self.ctl_n
        m = self.console.mark()
        self.links["ctl"].sendall(command.encode() + b"\n")
        i = self.console.wait(lambda it: it[1].startswith(f"CTL {n} rc="), m, timeout,
                              f"the guest to run `{command}`")
        return int(self.console.items[i][1].split("rc=")[1])

    def uhid(self, line):
        self.links["uhid"].sendall(line.encode() + b"\n")

    def command(self, name, timeout=5.0, **kw):
        cid = f"hil-{name}-{time.monotonic_ns()}"
        m = self.stream.mark()
        msg = {"type": "command", "id": cid, "name": name, **kw}
        self.links["stream"].sendall(json.dumps(msg).encode() + b"\n")
        i = self.stream.wait(lambda it: it[3].get("id") == cid and it[3].get("type") in ("ack", "error"),
                             m, timeout, f"the answer to command {name}")
        r = self.stream.items[i][3]
        if r["type"] != "ack":
            raise StepError(f"command {name} refused: {r.get('message')}")

    def stop(self, timeout=15.0):
        """Stops the daemon with SIGTERM (as systemd does) and waits for the guest."""
        if self.proc is None or self.proc.poll() is not None:
            return None
        rc = None
        try:
            m = self.console.mark()
            self.links["ctl"].sendall(b"kill -TERM $(cat /run/hil-daemon.pid)\n")
            i = self.console.wait(lambda it: it[1].startswith("HIL DAEMON EXIT"), m, timeout,
                                  "the daemon to exit after SIGTERM")
            rc = int(self.console.items[i][1].split("rc=")[1])
            self.proc.wait(timeout=10)
        except (StepError, subprocess.TimeoutExpired, OSError):
            pass
        finally:
            self.kill()
        return rc

    def kill(self):
        if self.proc is not None and self.proc.poll() is None:
            try:
                os.killpg(self.proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self.proc.wait()
        if self in _guests:
            _guests.remove(self)

    def daemon_log(self, start=0):
        return [t for _, t in self.console.since(start)]


# ------------------------------------------------------------------ checks and numbers
class Scenario:
    def __init__(self, name):
        self.name = name
        self.checks = []
        self.samples = {"total_ms": [], "daemon_ms": [], "daemon_serialise_ms": [], "transport_ms": []}
        self.notes = []

    def check(self, ok, what, detail=""):
        self.checks.append({"ok": bool(ok), "what": what, "detail": detail})
        print(f"    [{'ok' if ok else 'FAIL'}] {what}{(': ' + detail) if detail else ''}", flush=True)
        return ok

    def error(self, e):
        self.check(False, "scenario ran to the end", str(e))

    @property
    def passed(self):
        return bool(self.checks) and all(c["ok"] for c in self.checks)

    def latency(self):
        return {k: pct(v) for k, v in self.samples.items() if v}

    def json(self):
        return {"name": self.name, "passed": self.passed, "checks": self.checks,
                "latency_ms": self.latency(), "notes": self.notes}


def pct(v):
    v = sorted(v)
    if not v:
        return {}

    def q(p):
        return v[min(len(v) - 1, max(0, math.ceil(p * len(v)) - 1))]
    return {"n": len(v), "p50": round(q(0.50), 3), "p95": round(q(0.95), 3),
            "p99": round(q(0.99), 3), "max": round(v[-1], 3)}


def snapshots(items, conn=0):
    return [it for it in items if it[1] == conn and it[3].get("type") == "snapshot"]


def events(items, kind):
    return [it[3] for it in items if it[3].get("type") == kind]


def find_touch(snap, pos, tol):
    for t in snap.get("touches") or []:
        if abs(t["x"] - pos[0]) <= tol and abs(t["y"] - pos[1]) <= tol:
            return t
    return None


def match_touches(touches, expected, tol):
    """Whether `touches` (world) and `expected` positions pair up within tol."""
    if len(touches) != len(expected):
        return False, f"{len(touches)} touches, {len(expected)} expected"
    left = list(touches)
    worst = 0.0
    for p in expected:
        best = min(left, key=lambda t: (t["x"] - p[0]) ** 2 + (t["y"] - p[1]) ** 2)
        d = math.hypot(best["x"] - p[0], best["y"] - p[1])
        worst = max(worst, d)
        left.remove(best)
    return worst <= tol, f"worst {worst * 1000:.1f} mm"


def centroid(positions):
    n = len(positions) // 2
    return (sum(positions[0::2]) / n, sum(positions[1::2]) / n) if n else (math.nan, math.nan)


def latest_positions(g):
    snaps = snapshots(g.stream.since(0), conn=1)
    return snaps[-1][3]["positions"] if snaps else []


def wait_snapshot(g, pred, start, what, timeout=SNAPSHOT_TIMEOUT_S):
    i = g.stream.wait(lambda it: it[1] == 0 and it[3].get("type") == "snapshot" and pred(it[3]),
                      start, timeout, what)
    return g.stream.items[i]


def sample_latency(sc, t_send_ns, item):
    host_ns, _, guest_us, snap = item
    total = (host_ns - t_send_ns) / 1e6
    if snap.get("input_t_us") is None:
        return
    daemon = (guest_us - snap["input_t_us"]) / 1e3
    sc.samples["total_ms"].append(total)
    sc.samples["daemon_ms"].append(daemon)
    if snap.get("latency_us") is not None:
        sc.samples["daemon_serialise_ms"].append(snap["latency_us"] / 1e3)
    sc.samples["transport_ms"].append(total - daemon)


# ------------------------------------------------------------------ touch senders
class VirtioTouch:
    """Frames through QMP input-send-event to virtio-multitouch (one command, one frame)."""

    def __init__(self, g):
        self.g = g
        self.down = {}  # slot -> tracking id

    @staticmethod
    def dev(p):
        return (max(0, min(VIRTIO_MAX, round(p[0] / WORLD[0] * VIRTIO_MAX))),
                max(0, min(VIRTIO_MAX, round(p[1] / WORLD[1] * VIRTIO_MAX))))

    @staticmethod
    def world(d):
        return (d[0] / VIRTIO_MAX * WORLD[0], d[1] / VIRTIO_MAX * WORLD[1])

    def frame(self, moves, lifts=()):
        """moves: {slot: (tracking id, world pos)}; lifts: slots. Returns (t_send_ns,
        {slot: world position as the device reports it})."""
        ev = []
        if not self.down and moves:
            ev.append({"type": "btn", "data": {"button": "touch", "down": True}})
        out = {}
        for slot, (tid, p) in moves.items():
            x, y = self.dev(p)
            kind = "update" if slot in self.down else "begin"
            self.down[slot] = tid
            ev += [{"type": "mtt", "data": {"type": kind, "slot": slot, "tracking-id": tid, "axis": "x", "value": x}},
                   {"type": "mtt", "data": {"type": "data", "slot": slot, "tracking-id": tid, "axis": "x", "value": x}},
                   {"type": "mtt", "data": {"type": "data", "slot": slot, "tracking-id": tid, "axis": "y", "value": y}}]
            out[slot] = self.world((x, y))
        for slot in lifts:
            ev.append({"type": "mtt", "data": {"type": "end", "slot": slot, "tracking-id": -1, "axis": "x", "value": 0}})
            self.down.pop(slot, None)
        if lifts and not self.down:
            ev.append({"type": "btn", "data": {"button": "touch", "down": False}})
        t = time.monotonic_ns()
        self.g.qmp.cmd("input-send-event", events=ev)
        return t, out


class UhidTouch:
    """Frames as input reports of a real descriptor, through the guest's uhid bridge."""

    def __init__(self, g, layout, per_report=None):
        self.g, self.layout, self.per_report = g, layout, per_report
        self.down = {}  # contact id -> logical (x, y)
        self.scan = 0
        self.xr, self.yr = layout.x_range(), layout.y_range()
        self.reports_sent = 0

    def dev(self, p):
        (x0, x1), (y0, y1) = self.xr, self.yr
        return (max(x0, min(x1, round(x0 + p[0] / WORLD[0] * (x1 - x0)))),
                max(y0, min(y1, round(y0 + p[1] / WORLD[1] * (y1 - y0)))))

    def world(self, d):
        (x0, x1), (y0, y1) = self.xr, self.yr
        return ((d[0] - x0) / (x1 - x0) * WORLD[0], (d[1] - y0) / (y1 - y0) * WORLD[1])

    def frame(self, moves, lifts=()):
        out = {}
        for cid, (_, p) in moves.items():
            self.down[cid] = self.dev(p)
            out[cid] = self.world(self.down[cid])
        contacts = [(cid, x, y, True) for cid, (x, y) in self.down.items()]
        for cid in lifts:
            if cid in self.down:
                x, y = self.down.pop(cid)
                contacts = [c for c in contacts if c[0] != cid] + [(cid, x, y, False)]
        self.scan += 100  # 10 ms in the 100 us units of Scan Time
        reps = self.layout.reports(contacts, self.scan, self.per_report)
        t = time.monotonic_ns()
        for r in reps:
            self.g.uhid("I " + r.hex())
        self.reports_sent += len(reps)
        return t, out


# ------------------------------------------------------------------ configs
def config_ron(select, interface, agents=100):
    default = open(os.path.join(ROOT, "config", "crowdtouch.ron")).read()
    start = default.index("inputs:")
    end = default.index("surface:")
    inputs = ("inputs: [\n        Device(select: %s, interface: %s, grab: false, region: None,\n"
              "            calibration: (rotation: 0, flip_x: false, flip_y: false, matrix: None),\n"
              "            palm_max_mm: Some(30.0), size_mm: None),\n    ],\n\n    " % (select, interface))
    text = default[:start] + inputs + default[end:]
    return re.sub(r"agents: \d+,", f"agents: {agents},", text, count=1)


HELLO_FAST = json.dumps({"type": "hello", "protocol": 1, "subscribe": ["snapshot", "events", "stats"],
                         "fields": ["touches"]})
HELLO_CROWD = json.dumps({"type": "hello", "protocol": 1, "subscribe": ["snapshot"],
                          "fields": ["positions"], "max_rate_hz": 5})


def finger_layout(n, centre=FORMATION_CENTRE):
    if n == 1:
        return [centre]
    r = 0.6 if n == 2 else 0.75 if n <= 5 else 0.9
    return [(centre[0] + r * math.cos(2 * math.pi * k / n + 0.3), centre[1] + r * math.sin(2 * math.pi * k / n + 0.3))
            for k in range(n)]


KIND = {1: "point", 2: "line"}
MAX_CONTROL_FINGERS = 10  # gesture::segment::MAX_FINGERS: one control is at most two hands


# ------------------------------------------------------------------ scenarios
def gesture(g, sc, touch, n, ids, drag=(2.0, 0.6), frames=50, period_s=0.02, hold_s=2.0,
            settle_s=1.2, measure=True):
    """n fingers down on the crowd, a drag, staggered lifts; checks what the daemon
    published and how the crowd moved."""
    g.command("reset", hard=True)
    time.sleep(0.6)
    before = centroid(latest_positions(g))
    start = finger_layout(n)
    m0 = g.stream.mark()
    t, where = touch.frame({ids[k]: (100 + ids[k], start[k]) for k in range(n)})
    item = wait_snapshot(g, lambda s: len(s.get("touches") or []) == n, m0, f"a snapshot with {n} touches")
    if measure:
        sample_latency(sc, t, item)
    ok, d = match_touches(item[3]["touches"], list(where.values()), 0.003)
    sc.check(ok, f"{n} finger(s) down: the snapshot's touches are where they were put", d)
    time.sleep(0.05)
    last = where
    for f in range(1, frames + 1):
        a = f / frames
        pos = {ids[k]: (100 + ids[k], (start[k][0] + a * drag[0], start[k][1] + a * drag[1])) for k in range(n)}
        m = g.stream.mark()
        t, last = touch.frame(pos)
        want = last[ids[0]]
        try:
            item = wait_snapshot(g, lambda s: find_touch(s, want, 0.0015) is not None, m,
                                 f"the snapshot of drag frame {f}")
            if measure:
                sample_latency(sc, t, item)
        except StepError as e:
            sc.check(False, f"drag frame {f} reached the socket", str(e))
            break
        time.sleep(max(0.0, period_s - (time.monotonic_ns() - t) / 1e9))
    item = wait_snapshot(g, lambda s: find_touch(s, last[ids[0]], 0.0015) is not None, m0, "the last drag frame")
    ok, d = match_touches(item[3]["touches"], list(last.values()), 0.003)
    sc.check(ok, f"after the drag: {n} touches at the fingers' positions", d)
    time.sleep(hold_s)
    for k in reversed(range(n)):
        m = g.stream.mark()
        t, _ = touch.frame({}, lifts=[ids[k]])
        try:
            item = wait_snapshot(g, lambda s, k=k: len(s.get("touches") or []) == k, m,
                                 f"a snapshot with {k} touches after a lift")
            if measure:
                sample_latency(sc, t, item)
        except StepError as e:
            sc.check(False, f"lift {n - k} of {n} reached the socket", str(e))
        time.sleep(0.1)
    time.sleep(settle_s)
    seg = g.stream.since(m0)
    ctrl = events(seg, "control")
    last = {}
    for c in ctrl:
        if c["phase"] in ("begin", "update"):
            last[c["id"]] = c
    want_kind = KIND.get(n, "area")
    if n <= MAX_CONTROL_FINGERS:
        final = next(iter(last.values()), {})
        sc.check(len(last) == 1 and final.get("kind") == want_kind and len(final.get("fingers", [])) == n,
                 f"one {want_kind} control of {n} finger(s)",
                 f"controls {sorted(last)}, last begin/update: kind {final.get('kind')}, fingers {final.get('fingers')}")
    else:
        fingers = [f for c in last.values() for f in c.get("fingers", [])]
        want = math.ceil(n / MAX_CONTROL_FINGERS)
        sc.check(len(last) == want and len(set(fingers)) == n,
                 f"{n} fingers grabbed the crowd as {want} controls (at most {MAX_CONTROL_FINGERS} fingers each)",
                 ", ".join(f"{c['kind']} of {len(c.get('fingers', []))}" for c in last.values()))
    ends = [c for c in ctrl if c["phase"] == "end"]
    sc.check(len(ends) >= 1 and not any(c.get("cancelled") for c in ends),
             "the control ended by lifting (not cancelled)", f"{len(ends)} end event(s)")
    tail = snapshots(g.stream.since(g.stream.mark() - 5))
    sc.check(bool(tail) and all(not (s[3].get("touches") or []) for s in tail),
             "no touch left down after the lifts")
    after = centroid(latest_positions(g))
    moved = (after[0] - before[0], after[1] - before[1])
    err = math.hypot(moved[0] - drag[0], moved[1] - drag[1])
    sc.check(err <= 0.35, f"the crowd followed the drag ({drag[0]:+.1f}, {drag[1]:+.1f}) m",
             f"centroid moved ({moved[0]:+.2f}, {moved[1]:+.2f}) m, off by {err:.2f} m")
    return moved


def scenario_evdev_fingers(g, n):
    sc = Scenario(f"evdev-{n}")
    try:
        gesture(g, sc, VirtioTouch(g), n, list(range(n)))
    except StepError as e:
        sc.error(e)
    return sc


def tap(g, touch, key, pos, what):
    """One finger down at `pos` and up again; both must reach the socket."""
    m = g.stream.mark()
    touch.frame({key: (key + 40, pos)})
    wait_snapshot(g, lambda s: len(s.get("touches") or []) == 1, m, what)
    touch.frame({}, lifts=[key])
    wait_snapshot(g, lambda s: not s.get("touches"), m, f"the lift after {what}")


def device_add(g):
    """Adds virtio-multitouch back; QEMU finishes a device_del only once the guest has
    ejected the device, so an early add is retried."""
    deadline = time.monotonic() + 10
    while True:
        try:
            return g.qmp.cmd("device_add", driver="virtio-multitouch-pci", id="mt0", bus="rp1")
        except StepError as e:
            if "Duplicate" not in str(e) or time.monotonic() > deadline:
                raise
            time.sleep(0.1)


def wait_device(g, state, start, timeout=20.0):
    i = g.stream.wait(lambda it: it[3].get("type") == "device" and it[3].get("state") == state,
                      start, timeout, f"a `device` event `{state}`")
    return g.stream.items[i][3]


def scenario_evdev_hotplug(g):
    sc = Scenario("evdev-hotplug")
    try:
        g.command("reset", hard=True)
        time.sleep(0.3)
        touch = VirtioTouch(g)
        m = g.stream.mark()
        touch.frame({0: (7, (7.6, 4.5)), 1: (8, (8.4, 4.5))})
        wait_snapshot(g, lambda s: len(s.get("touches") or []) == 2, m, "two touches")
        for k in range(10):
            touch.frame({0: (7, (7.6 + 0.05 * k, 4.5)), 1: (8, (8.4 + 0.05 * k, 4.5))})
            time.sleep(0.02)
        m = g.stream.mark()
        g.qmp.cmd("device_del", id="mt0")
        ev = wait_device(g, "unplugged", m)
        sc.check(True, "`device` unplugged published", ev.get("message", ""))
        item = wait_snapshot(g, lambda s: not s.get("touches"), m, "a snapshot with no touches")
        ctrl = [c for c in events(g.stream.since(m), "control") if c["phase"] == "end"]
        sc.check(bool(ctrl) and all(c.get("cancelled") for c in ctrl),
                 "the unplugged device's control ended as cancelled", f"{len(ctrl)} end event(s)")
        sc.check(True, "no touch stuck after the unplug")
        time.sleep(0.5)
        m2 = g.stream.mark()
        snaps = snapshots(g.stream.since(m))
        sc.check(len(snaps) > 10, "the daemon kept publishing while the device was gone", f"{len(snaps)} snapshots")
        device_add(g)
        ev = wait_device(g, "attached", m2)
        sc.check(True, "`device` attached again", f"{ev.get('node')} id {ev.get('stable_id')}")
        tap(g, VirtioTouch(g), 0, (8.0, 4.5), "a touch on the re-added device")
        sc.check(True, "touches on the re-added device reach the socket")
    except StepError as e:
        sc.error(e)
    return sc


def scenario_evdev_overload(g):
    sc = Scenario("evdev-overload")
    try:
        g.command("reset", hard=True)
        time.sleep(0.3)
        touch = VirtioTouch(g)
        m = g.stream.mark()
        touch.frame({0: (21, (7.0, 4.0)), 1: (22, (9.0, 5.0))})
        item = wait_snapshot(g, lambda s: len(s.get("touches") or []) == 2, m, "two touches")
        lifted_id = find_touch(item[3], touch.world(touch.dev((9.0, 5.0))), 0.003)["id"]
        log0 = g.console.mark()
        if g.ctl("kill -STOP $(cat /run/hil-daemon.pid)") != 0:
            raise StepError("could not SIGSTOP the daemon")
        # While it is stopped: finger 1 lifts, finger 2 lands, finger 0 moves a lot;
        # far more events than the kernel's evdev client buffer holds.
        touch.frame({}, lifts=[1])
        touch.frame({2: (23, (8.0, 3.5))})
        n = 400
        for k in range(n):
            touch.frame({0: (21, (7.0 + 1.5 * (k + 1) / n, 4.0))})
        # QEMU itself drops virtio-input frames when the guest's queue is full (a
        # transport limit, not the kernel's): let the guest drain it, then put every
        # finger at its final place once more, still with the daemon stopped.
        time.sleep(0.5)
        touch.frame({0: (21, (8.6, 4.0)), 2: (23, (8.0, 3.5))})
        time.sleep(0.2)
        final = {0: touch.world(touch.dev((8.6, 4.0))), 2: touch.world(touch.dev((8.0, 3.5)))}
        m = g.stream.mark()
        if g.ctl("kill -CONT $(cat /run/hil-daemon.pid)") != 0:
            raise StepError("could not SIGCONT the daemon")
        item = wait_snapshot(g, lambda s: match_touches(s.get("touches") or [], list(final.values()), 0.003)[0],
                             m, "the resynchronised touches", timeout=10)
        sc.check(True, "after the resume the touches are exactly the fingers on the glass",
                 match_touches(item[3]["touches"], list(final.values()), 0.003)[1])
        i = g.console.wait(lambda it: "SYN_DROPPED" in it[1], log0, 5, "the daemon's SYN_DROPPED log line")
        sc.check(True, "the kernel reported SYN_DROPPED and the daemon said so", g.console.items[i][1][-160:])
        after = g.stream.items.index(item)
        later = {t["id"] for it in snapshots(g.stream.since(after)) for t in it[3].get("touches") or []}
        sc.check(lifted_id not in later, "the finger lifted during the stall is gone (cancelled by the resync)",
                 f"touch ids after the resume {sorted(later)}, lifted {lifted_id}")
        m = g.stream.mark()
        touch.frame({}, lifts=[0, 2])
        wait_snapshot(g, lambda s: not s.get("touches"), m, "no touches after the last lifts")
        sc.check(True, "no stuck touch after the final lifts")
    except StepError as e:
        sc.error(e)
    return sc


def scenario_evdev_permissions(g):
    sc = Scenario("evdev-permissions")
    try:
        udev = [t for _, t in g.console.since(0) if t.startswith("UDEV add /dev/input/event")]
        applied = [t for t in udev if "rule=applied" in t]
        sc.check(bool(applied) and all(f"group={g.args.rule[0]}" in t and f"mode={g.args.rule[1]}" in t for t in applied),
                 "the udev rule's group and mode were on the touchscreen node the daemon read (as uid 900)",
                 applied[0] if applied else "no node got the rule")
        m = g.stream.mark()
        g.ctl("touch /tmp/hil-deny")
        g.qmp.cmd("device_del", id="mt0")
        wait_device(g, "unplugged", m)
        m = g.stream.mark()
        log0 = g.console.mark()
        device_add(g)
        try:
            i = g.stream.wait(lambda it: it[3].get("type") == "device" and it[3].get("state") == "failed"
                              and "permission denied" in (it[3].get("message") or ""), m, 30,
                              "a `device` event `failed` saying permission denied")
            msg = g.stream.items[i][3].get("message") or ""
        except StepError as e:
            msg = str(e)
        sc.check("permission denied" in msg and "udev rule" in msg,
                 "an unreadable node gives the documented permission error", msg)
        i = g.console.wait(lambda it: it[1].startswith("UDEV add /dev/input/event") and "rule=denied" in it[1],
                           log0, 5, "the node left root 0600")
        node = g.console.items[i][1].split()[2]
        m = g.stream.mark()
        g.ctl(f"rm /tmp/hil-deny; chgrp {g.args.rule[0]} {node}; chmod {g.args.rule[1]} {node}")
        ev = wait_device(g, "attached", m, timeout=15)
        sc.check(True, "once the rule's group and mode are set, the daemon attaches by itself", ev.get("node", ""))
        tap(g, VirtioTouch(g), 0, (8.0, 4.5), "a touch after the fix")
        sc.check(True, "touches flow after the permissions were fixed")
    except StepError as e:
        sc.error(e)
    return sc


HID_DEVICES = [
    # name, fixture, vendor, product, fingers. A device fills each report with as many
    # contacts as it holds (parallel); a frame with more contacts continues in the next
    # reports, whose Contact Count is 0 (hybrid).
    ("3m-parallel-10-per-report-rid16", "3m_0596_0500.rdesc", 0x0596, 0x0500, 5),
    ("zytronic-hybrid-12-fingers-in-2-reports", "zytronic_14c8_0006.rdesc", 0x14C8, 0x0006, 12),
    ("ite-touchpad-hybrid-1-per-report-rid3", "ite_06cb_2968.rdesc", 0x06CB, 0x2968, 5),
]


def contact_ids(layout, n):
    """n distinct Contact Identifiers the device's field can hold."""
    f = layout.fingers[0].get(hidgen.CONTACT_ID)
    # Many descriptors leave the logical range of Contact Identifier at the Tip
    # Switch's 0..1; the field's size is what bounds the values a device sends.
    hi = min(255, max(f.lmax, (1 << f.size) - 1)) if f else 255
    if n > hi + 1:
        raise StepError(f"{n} fingers but the Contact Identifier only goes to {hi}")
    return [(1 + k) % (hi + 1) for k in range(n)]


def uhid_create(g, layout, vid, pid, name, rd):
    for rid, data in layout.feature_replies():
        g.uhid(f"F {rid} {data.hex()}")
    g.uhid(f"C {vid:04x} {pid:04x} {name} {rd.hex()}")


def scenario_hidraw(g, name, rd, layout, fingers, vid, pid, hotplug):
    sc = Scenario(f"hidraw-{name}")
    results = [sc]
    try:
        m = g.stream.mark()
        uhid_create(g, layout, vid, pid, name, rd)
        ev = wait_device(g, "attached", m, timeout=30)
        sc.check(True, f"the daemon found and opened the hidraw node itself", f"{ev.get('node')} ({ev.get('name')})")
        n = min(fingers, layout.max_contacts)
        touch = UhidTouch(g, layout)
        gesture(g, sc, touch, n, contact_ids(layout, n), frames=40)
        sc.notes.append(f"{touch.reports_sent} input reports sent; descriptor {len(rd)} bytes, report id "
                        f"{layout.report_id}, {layout.per_report} contact(s) per report, {n} fingers")
    except StepError as e:
        sc.error(e)
    if hotplug:
        hp = Scenario("hidraw-hotplug")
        results.append(hp)
        try:
            touch = UhidTouch(g, layout)
            m = g.stream.mark()
            g.command("reset", hard=True)
            time.sleep(0.3)
            touch.frame({1: (0, (7.5, 4.5)), 2: (0, (8.5, 4.5))})
            wait_snapshot(g, lambda s: len(s.get("touches") or []) == 2, m, "two touches")
            m = g.stream.mark()
            g.uhid("X")
            ev = wait_device(g, "unplugged", m)
            hp.check(True, "`device` unplugged published when the HID device was destroyed", ev.get("message", ""))
            wait_snapshot(g, lambda s: not s.get("touches"), m, "a snapshot with no touches")
            ends = [c for c in events(g.stream.since(m), "control") if c["phase"] == "end"]
            hp.check(bool(ends) and all(c.get("cancelled") for c in ends), "its control ended as cancelled",
                     f"{len(ends)} end event(s)")
            m = g.stream.mark()
            uhid_create(g, layout, vid, pid, name, rd)
            ev = wait_device(g, "attached", m, timeout=30)
            hp.check(True, "the re-created device was attached again", ev.get("node", ""))
            tap(g, UhidTouch(g, layout), 3, (8.0, 4.5), "a touch after re-creation")
            hp.check(True, "touches flow again, none stuck")
        except StepError as e:
            hp.error(e)
    return results


# ------------------------------------------------------------------ runs
def shutdown(g):
    """SIGTERM to the daemon, as systemd sends it: a clean exit and `bye` to clients."""
    m = g.stream.mark()
    rc = g.stop()
    seg = g.stream.since(m)
    byes = [it for it in seg if it[3].get("type") == "bye"]
    panics = [t for t in g.daemon_log() if "panicked" in t]
    res = Scenario(f"{g.name}-shutdown")
    res.check(rc == 0, "SIGTERM stops the daemon cleanly (exit 0)", f"rc={rc}")
    res.check(bool(byes), "clients got `bye`")
    res.check(not panics, "no panic in the daemon's log", panics[0] if panics else "")
    return res


def run_guest(g, results, body):
    """Runs `body(g)` (which returns its scenarios) on a booted guest, then the shutdown
    scenario; a failed step becomes a failed scenario named after the guest, with the
    end of the guest's console. The guest is killed whatever happens."""
    out = []
    try:
        print(f"  {g.wait_ready()}", flush=True)
        out += body(g)
        out.append(shutdown(g))
    except StepError as e:
        sc = Scenario(f"{g.name}-guest")
        sc.error(e)
        out.append(sc)
        tail = "\n".join(g.daemon_log()[-25:])
        print(f"  guest console (last lines):\n{tail}", flush=True)
    finally:
        g.kill()
    results += out


def run_evdev(args, results):
    want = [s for s in ("evdev-1", "evdev-2", "evdev-3", "evdev-5", "evdev-hotplug", "evdev-overload",
                        "evdev-permissions") if selected(args, s)]
    if not want:
        return
    scenarios = {"evdev-hotplug": scenario_evdev_hotplug, "evdev-overload": scenario_evdev_overload,
                 "evdev-permissions": scenario_evdev_permissions}

    def body(g):
        wait_device(g, "attached", 0, timeout=30)
        g.stream.wait(lambda it: it[1] == 1 and it[3].get("type") == "snapshot", 0, 10, "the crowd stream")
        print(f"  booted in {g.boot_s:.1f} s; daemon attached", flush=True)
        out = []
        for name in want:
            print(f"  -- {name}", flush=True)
            if name[6:].isdigit():
                out.append(scenario_evdev_fingers(g, int(name[6:])))
            else:
                out.append(scenarios[name](g))
        return out

    print("== guest: virtio-multitouch (evdev)", flush=True)
    run_guest(Guest("evdev", args, config_ron("Auto", "Evdev"),
                    ["-device", "virtio-multitouch-pci,id=mt0,bus=rp1"], (HELLO_FAST, HELLO_CROWD)),
              results, body)


def run_hidraw(args, results):
    for k, (name, fixture, vid, pid, fingers) in enumerate(HID_DEVICES):
        hotplug = k == 0 and selected(args, "hidraw-hotplug")
        if not selected(args, f"hidraw-{name}") and not hotplug:
            continue
        rd = open(os.path.join(ROOT, "tests", "fixtures", "hid", "descriptors", fixture), "rb").read()
        layout = hidgen.Descriptor(rd).touch_collections()[0]

        def body(g, name=name, rd=rd, layout=layout, fingers=fingers, vid=vid, pid=pid, hotplug=hotplug):
            g.console.wait(lambda it: it[1].startswith("BRIDGE READY"), 0, 10, "the uhid bridge")
            g.stream.wait(lambda it: it[1] == 1 and it[3].get("type") == "snapshot", 0, 20, "the crowd stream")
            return scenario_hidraw(g, name, rd, layout, fingers, vid, pid, hotplug)

        print(f"== guest: uhid {name} ({fixture}, {vid:04x}:{pid:04x})", flush=True)
        run_guest(Guest(f"hidraw-{name}", args, config_ron(f'VendorProduct("{vid:04x}:{pid:04x}")', "Hidraw"),
                        [], (HELLO_FAST, HELLO_CROWD)), results, body)


def selected(args, name):
    return not args.only or any(name == o or name.startswith(o + "-") or o == name.split("-")[0]
                                for o in args.only)


def read_rule(path):
    """(evdev group id, mode, hidraw group id, mode) from the project's udev rule."""
    text = open(path).read()
    ev = re.search(r'SUBSYSTEM=="input".*GROUP="([^"]+)".*MODE="([0-7]+)"', text)
    hid = re.search(r'SUBSYSTEM=="hidraw".*DRIVERS=="hid-multitouch".*GROUP="([^"]+)".*MODE="([0-7]+)"', text)
    if not ev or not hid:
        raise StepError(f"{path}: no GROUP/MODE for input and hid-multitouch hidraw nodes")
    for grp in (ev.group(1), hid.group(1)):
        if grp != "crowdtouch":
            raise StepError(f"{path}: group {grp}; the guest only has the crowdtouch group")
    return (str(DAEMON_UID), ev.group(2), str(DAEMON_UID), hid.group(2))


def table(results):
    rows = ["| scenario | result | samples | total p50 / p95 / p99 ms | daemon p50 / p95 / p99 ms | transport p50 / p95 / p99 ms |",
            "|---|---|---|---|---|---|"]
    for r in results:
        lat = r.latency()

        def f(k):
            v = lat.get(k)
            return f"{v['p50']:.2f} / {v['p95']:.2f} / {v['p99']:.2f}" if v else "–"
        n = lat.get("total_ms", {}).get("n", 0)
        rows.append(f"| {r.name} | {'pass' if r.passed else 'FAIL'} | {n or '–'} | {f('total_ms')} | "
                    f"{f('daemon_ms')} | {f('transport_ms')} |")
    return "\n".join(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kernel", required=True)
    ap.add_argument("--initrd", required=True)
    ap.add_argument("--accel", default="tcg")
    ap.add_argument("--cpu", default=None)
    ap.add_argument("--only", default="", help="comma-separated scenario names or prefixes (evdev, hidraw)")
    ap.add_argument("--json", default=None)
    ap.add_argument("--workdir", default=os.path.join(ROOT, "target", "hil-guest", "run"))
    ap.add_argument("--udev-rule", default=os.path.join(ROOT, "udev", "70-crowdtouch.rules"))
    args = ap.parse_args()
    args.only = [o for o in args.only.split(",") if o]
    os.makedirs(args.workdir, exist_ok=True)
    t0 = time.monotonic()
    results = []
    try:
        args.rule = read_rule(args.udev_rule)
        run_evdev(args, results)
        run_hidraw(args, results)
    except StepError as e:
        sc = Scenario("harness")
        sc.error(e)
        results.append(sc)
    finally:
        _kill_all()
    wall = time.monotonic() - t0
    print("\n" + table(results))
    print(f"\naccel {args.accel}; {len(results)} scenario groups in {wall:.0f} s; "
          f"latencies under software emulation are inflated (see hil/README.md)")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"accel": args.accel, "wall_s": round(wall, 1),
                       "scenarios": [r.json() for r in results]}, f, indent=1)
    failed = [r.name for r in results if not r.passed]
    if failed:
        print(f"FAILED: {', '.join(failed)}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
