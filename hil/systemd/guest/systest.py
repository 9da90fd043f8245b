#!/usr/bin/python3
"""The system test's guest side: run by systest.service at boot of a Debian 12 guest
with systemd, it installs the crowdtouch package with apt and checks the service as
a kiosk meets it. Every check is one JSON line on /dev/ttyS1 ({"check", "ok",
"detail"}); the last line is {"done": true}. Then the guest powers off.

The host (hil/systemd/host.py) listens for TUIO datagrams on the address the guest
reaches as 10.0.2.2 (QEMU's user network), and passes its port on the kernel
command line as systest.tuio_port=N.
"""
import json
import os
import re
import socket
import subprocess
import sys
import time
import urllib.request

HERE = "/opt/systest"
CONFIG = "/etc/crowdtouch/crowdtouch.ron"
SOCKET = "/run/crowdtouch/crowdtouch.sock"
RULE = "/usr/lib/udev/rules.d/70-crowdtouch.rules"
DROPIN = "/run/systemd/generator/crowdtouch.service.d/50-crowdtouch-network.conf"
RESULTS = open("/dev/ttyS1", "w", buffering=1)
T0 = time.monotonic()
failures = 0

sys.path.insert(0, HERE)
import hidgen  # noqa: E402  (the HIL's independent HID report encoder)


def log(msg):
    print(f"systest [{time.monotonic() - T0:6.1f}s] {msg}", flush=True)


def result(name, ok, detail=""):
    global failures
    failures += 0 if ok else 1
    RESULTS.write(json.dumps({"check": name, "ok": bool(ok), "detail": str(detail)[:2000],
                              "t_s": round(time.monotonic() - T0, 1)}) + "\n")
    log(f"{'ok  ' if ok else 'FAIL'} {name}: {str(detail)[:300]}")


def sh(cmd, check=False, timeout=120, **kw):
    r = subprocess.run(cmd, shell=isinstance(cmd, str), capture_output=True, text=True,
                       timeout=timeout, **kw)
    if check and r.returncode != 0:
        raise RuntimeError(f"{cmd}: exit {r.returncode}: {r.stderr.strip()[-500:]}")
    return r


def wait(what, cond, timeout, step=0.25):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        v = cond()
        if v:
            return v
        time.sleep(step)
    return None


def active():
    return sh("systemctl is-active crowdtouch").stdout.strip() == "active"


def main_pid():
    return sh("systemctl show -p MainPID --value crowdtouch").stdout.strip()


def doctor():
    r = sh("crowdtouch doctor --json", timeout=60)
    try:
        v = json.loads(r.stdout)
    except ValueError:
        return r.returncode, {"ok": None, "checks": [], "raw": r.stdout + r.stderr}
    return r.returncode, v


def doctor_check(v, name):
    for c in v.get("checks", []):
        if c["name"] == name:
            return c
    return None


def client(user, seconds, until):
    """A socket client run as `user` (client.py): its JSON summary."""
    r = sh(["runuser", "-u", user, "--", "python3", f"{HERE}/client.py", SOCKET, str(seconds), until],
           timeout=seconds + 30)
    try:
        return json.loads(r.stdout.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return {"connected": False, "error": (r.stdout + r.stderr)[-500:]}


def edit_config(fn):
    text = open(CONFIG).read()
    open(CONFIG, "w").write(fn(text))


class Touch:
    """A uhid digitizer (the 3M descriptor) through the HIL's uhid bridge."""

    def __init__(self):
        rd = open(f"{HERE}/touch.rdesc", "rb").read()
        self.layout = hidgen.Descriptor(rd).touch_collections()[0]
        os.mkfifo("/run/uhid.fifo")
        self.bridge = subprocess.Popen([f"{HERE}/uhidbridge", "/run/uhid.fifo"],
                                       stdout=open("/run/uhid.log", "w"), stderr=subprocess.STDOUT)
        self.fifo = open("/run/uhid.fifo", "w", buffering=1)
        for rid, data in self.layout.feature_replies():
            self.fifo.write(f"F {rid} {data.hex()}\n")
        self.fifo.write(f"C 0596 0500 crowdtouch-systest-3M {rd.hex()}\n")
        self.scan = 0

    def frame(self, contacts):
        self.scan += 100
        for r in self.layout.reports(contacts, self.scan):
            self.fifo.write("I " + r.hex() + "\n")

    def drag(self, frames=60):
        (x0, x1), (y0, y1) = self.layout.x_range(), self.layout.y_range()
        cid = 1
        for k in range(frames):
            f = k / (frames - 1)
            x = round(x0 + (0.45 + 0.2 * f) * (x1 - x0))
            y = round(y0 + 0.5 * (y1 - y0))
            self.frame([(cid, x, y, True)])
            time.sleep(1 / 60)
        self.frame([(cid, x, y, False)])


def uhid_nodes():
    """The nodes of the test digitizer the daemon may read: its hidraw node (bound to
    hid-multitouch) and its touchscreen event node, as udev sees them."""
    out = []
    for cls in ("hidraw", "input"):
        base = f"/sys/class/{cls}"
        for n in sorted(os.listdir(base)):
            if not re.fullmatch(r"(hidraw|event)\d+", n):
                continue
            if "0596:0500" not in os.path.realpath(f"{base}/{n}").upper():
                continue
            node = f"/dev/{'input/' if cls == 'input' else ''}{n}"
            props = sh(["udevadm", "info", "-q", "property", "-n", node]).stdout
            if cls == "hidraw" or "ID_INPUT_TOUCHSCREEN=1" in props:
                out.append(node)
    return out


def run():
    port = re.search(r"systest\.tuio_port=(\d+)", open("/proc/cmdline").read())
    tuio_port = int(port.group(1)) if port else 3333

    # 1. The package, with apt.
    t = time.monotonic()
    r = sh(f"DEBIAN_FRONTEND=noninteractive apt-get install -y {HERE}/crowdtouch.deb",
           timeout=300)
    result("apt_install", r.returncode == 0,
           f"{time.monotonic() - t:.1f} s; " + (r.stdout + r.stderr).strip()[-400:])
    if r.returncode != 0:
        return
    pw, gr = sh("getent passwd crowdtouch").stdout.strip(), sh("getent group crowdtouch").stdout.strip()
    uid = int(pw.split(":")[2]) if pw else -1
    result("user_and_group", bool(pw and gr) and 0 < uid < 1000, f"{pw} / {gr}")
    ready = wait("active", active, 60)
    result("service_ready", ready, sh("systemctl status --no-pager crowdtouch").stdout[-600:])
    dropin = open(DROPIN).read() if os.path.exists(DROPIN) else ""
    result("no_network_without_network_outputs", "PrivateNetwork=yes" in dropin
           and sh("systemctl show -p PrivateNetwork --value crowdtouch").stdout.strip() == "yes", dropin)

    # 2. A touch device appears and is read; clients in and out of the group.
    sh("useradd -m -G crowdtouch renderer && useradd -m outsider", check=True)
    import threading
    seen = {}
    th = threading.Thread(target=lambda: seen.update(client("renderer", 40, "touches")))
    th.start()
    time.sleep(2)
    touch = Touch()
    attached = wait("attached", lambda: "reading" in sh(
        "journalctl -u crowdtouch -b --no-pager -o cat").stdout, 30)
    nodes = uhid_nodes()
    modes = {n: oct(os.stat(n).st_mode & 0o777) + " gid " + str(os.stat(n).st_gid) for n in nodes}
    applied = bool(nodes) and all(os.stat(n).st_gid == int(gr.split(":")[2]) for n in nodes)
    # udevd read the rule only once the group existed (the package's preinst).
    unknown = "Unknown group 'crowdtouch'" in sh("journalctl -b -u systemd-udevd --no-pager -o cat").stdout
    applied = applied and not unknown
    why = ""
    if not applied:
        # What udev makes of the rule for these nodes, and what it logged.
        for n in nodes:
            sysp = "/sys/class/" + ("hidraw/" if "hidraw" in n else "input/") + os.path.basename(n)
            t = sh(["udevadm", "test", "--action=change", sysp]).stdout
            t += sh(["udevadm", "test", "--action=change", sysp]).stderr
            why += f"\n{n}: " + " | ".join(l for l in t.splitlines()
                                          if re.search(r"crowdtouch|GROUP|group", l))[-700:]
        why += "\nudevd: " + " | ".join(sh("journalctl -b -u systemd-udevd --no-pager -o cat")
                                        .stdout.splitlines()[-12:])
    result("udev_rule_applied", attached and applied, f"{modes}{why}")
    for _ in range(3):
        touch.drag()
        time.sleep(0.5)
    th.join()
    result("device_read_by_the_service", seen.get("touch_events", 0) >= 1 and seen.get("attached"),
           json.dumps(seen)[:600])
    result("group_member_gets_snapshots", seen.get("snapshots", 0) > 10, json.dumps(seen)[:300])
    out = client("outsider", 3, "none")
    result("outsider_refused", not out.get("connected") and "ermission" in out.get("error", ""),
           json.dumps(out)[:300])

    # 3. Network outputs: the unit opens what the config names after daemon-reload.
    outputs = (f'outputs: [Tuio(target: "10.0.2.2:{tuio_port}", privileged: true), '
               f'WebSocket(listen: "127.0.0.1:8080", metrics: true)],\n    inputs: [')
    edit_config(lambda s: s.replace("inputs: [", outputs, 1))
    r = sh(f"crowdtouch check-config {CONFIG}")
    result("check_config_warns_before_reload", r.returncode == 0 and "would block" in r.stderr,
           r.stderr.strip()[-500:])
    sh("systemctl daemon-reload && systemctl restart crowdtouch", check=True)
    result("service_ready_with_outputs", wait("active", active, 60),
           open(DROPIN).read() if os.path.exists(DROPIN) else "no drop-in")
    r = sh(f"crowdtouch check-config {CONFIG}")
    result("check_config_quiet_after_reload", r.returncode == 0 and "would block" not in r.stderr,
           r.stderr.strip()[-300:])
    touch.drag()
    time.sleep(2)
    result("tuio_sent", True, f"to 10.0.2.2:{tuio_port} (the host counts what arrived)")
    RESULTS.write(json.dumps({"tuio_port": tuio_port, "t_s": round(time.monotonic() - T0, 1)}) + "\n")
    try:
        page = urllib.request.urlopen("http://127.0.0.1:8080/", timeout=10).read().decode()
        result("viewer_served", "<html" in page.lower() and "WebSocket" in page, f"{len(page)} bytes")
    except OSError as e:
        result("viewer_served", False, e)
    for origin, want in (("http://127.0.0.1:8080", "101"), ("http://evil.example", "403")):
        s = socket.create_connection(("127.0.0.1", 8080), timeout=10)
        s.sendall(("GET /ws HTTP/1.1\r\nHost: 127.0.0.1:8080\r\nUpgrade: websocket\r\n"
                   "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                   f"Sec-WebSocket-Version: 13\r\nOrigin: {origin}\r\n\r\n").encode())
        head = s.recv(4096).decode(errors="replace")
        s.close()
        result(f"viewer_origin_{'own' if want == '101' else 'foreign'}", head.split(" ")[1:2] == [want],
               head.splitlines()[0] if head else "no answer")
    try:
        m = urllib.request.urlopen("http://127.0.0.1:8080/metrics", timeout=10).read().decode()
        touches = re.search(r"^crowdtouch_touches_total (\d+)", m, re.M)
        result("metrics_served", touches is not None, touches.group(0) if touches else m[:300])
    except OSError as e:
        result("metrics_served", False, e)

    # 4. doctor: healthy, then each planted fault named with its fix.
    code, v = doctor()
    bad = [c for c in v.get("checks", []) if not c["ok"]]
    result("doctor_healthy", code == 0 and v.get("ok") is True, json.dumps(bad or v)[:1500])
    for n in nodes:
        os.chmod(n, 0o600)
    code, v = doctor()
    c = doctor_check(v, "device_access") or {}
    result("doctor_finds_unreadable_node", code == 1 and c.get("ok") is False
           and "udevadm trigger" in (c.get("fix") or ""), json.dumps(c))
    # The fix doctor names, as the person at the kiosk would run it.
    fix = (c.get("fix") or "")
    start = fix.find("sudo systemctl restart systemd-udevd")
    cmd = fix[start:].replace("sudo ", "") if start >= 0 else ""
    sh(f"{cmd} && udevadm settle" if cmd else "false")
    code, v = doctor()
    c = doctor_check(v, "device_access") or {}
    result("doctor_fix_for_the_node_works", c.get("ok") is True, json.dumps(c))
    os.rename(RULE, "/root/rule.away")
    code, v = doctor()
    c = doctor_check(v, "udev_rule") or {}
    result("doctor_finds_missing_udev_rule", code == 1 and c.get("ok") is False
           and "70-crowdtouch.rules" in (c.get("fix") or ""), json.dumps(c))
    os.rename("/root/rule.away", RULE)
    saved = open(CONFIG).read()
    edit_config(lambda s: s.replace(f"10.0.2.2:{tuio_port}", "203.0.113.9:3333"))
    code, v = doctor()
    c = doctor_check(v, "output outputs[0].target") or {}
    result("doctor_finds_tuio_target_blocked_by_the_unit", code == 1 and c.get("ok") is False
           and "daemon-reload" in (c.get("fix") or ""), json.dumps(c))
    default = sh("ip route show default").stdout.strip()
    sh("systemctl daemon-reload && ip route del default")
    code, v = doctor()
    c = doctor_check(v, "output outputs[0].target") or {}
    result("doctor_finds_unreachable_tuio_target", code == 1 and c.get("ok") is False
           and "unreachable" in c.get("detail", ""), json.dumps(c) + f" (default route was: {default})")
    if default:
        sh(f"ip route add {default}")
    open(CONFIG, "w").write(saved)
    edit_config(lambda s: s.replace("path: None", 'path: Some("/nonexistent/dir/ct.sock")', 1))
    code, v = doctor()
    c = doctor_check(v, "socket") or {}
    result("doctor_finds_socket_in_missing_directory", code == 1 and c.get("ok") is False
           and "/nonexistent/dir" in c.get("detail", ""), json.dumps(c))
    open(CONFIG, "w").write(saved)
    sh("systemctl daemon-reload")

    # 5. systemctl reload applies a changed agent count.
    edit_config(lambda s: re.sub(r"agents: \d+,", "agents: 60,", s, count=1))
    sh("systemctl reload crowdtouch", check=True)
    st = client("renderer", 15, "agents=60")
    result("reload_applies_agent_count", st.get("agents") == 60, json.dumps(st)[:300])

    # 6. A stalled daemon is restarted by the watchdog.
    pid = main_pid()
    n0 = sh("systemctl show -p NRestarts --value crowdtouch").stdout.strip()
    sh(f"kill -STOP {pid}")
    restarted = wait("restart", lambda: main_pid() not in ("0", pid, "") and active(), 40)
    j = sh("journalctl -u crowdtouch -b --no-pager -o cat").stdout
    result("watchdog_restarts_a_stalled_daemon", restarted and "atchdog" in j,
           f"MainPID {pid} -> {main_pid()}, NRestarts {n0} -> "
           f"{sh('systemctl show -p NRestarts --value crowdtouch').stdout.strip()}")

    # 7. The journal: the daemon's priorities, no timestamp of its own.
    entries = [json.loads(line) for line in sh(
        "journalctl -u crowdtouch -b -o json --no-pager _COMM=crowdtouch").stdout.splitlines() if line]
    prios = sorted({e.get("PRIORITY") for e in entries})
    stamped = [e["MESSAGE"] for e in entries if isinstance(e.get("MESSAGE"), str)
               and re.match(r"^\[?\d{4}-\d\d-\d\d", e["MESSAGE"])]
    result("journal_priorities_no_double_timestamps",
           entries and not stamped and "6" in prios and "4" in prios
           and all(e.get("SYSLOG_IDENTIFIER") == "crowdtouch" for e in entries),
           f"{len(entries)} entries, priorities {prios}, stamped {stamped[:2]}")

    # 8. remove keeps the config, purge removes it.
    r = sh("DEBIAN_FRONTEND=noninteractive apt-get remove -y crowdtouch", timeout=120)
    gone = sh("systemctl is-active crowdtouch").stdout.strip()
    result("apt_remove_stops_and_keeps_config", r.returncode == 0 and gone != "active"
           and os.path.exists(CONFIG) and not os.path.exists("/usr/bin/crowdtouch"),
           f"is-active {gone}; config kept: {os.path.exists(CONFIG)}")
    r = sh("DEBIAN_FRONTEND=noninteractive apt-get purge -y crowdtouch", timeout=120)
    result("apt_purge_removes_config", r.returncode == 0 and not os.path.exists("/etc/crowdtouch"),
           f"/etc/crowdtouch exists: {os.path.exists('/etc/crowdtouch')}")


def main():
    log("starting")
    try:
        run()
    except Exception as e:  # a step that could not run is a failure, named
        result("step", False, f"{type(e).__name__}: {e}")
    RESULTS.write(json.dumps({"done": True, "failures": failures,
                              "t_s": round(time.monotonic() - T0, 1)}) + "\n")
    RESULTS.flush()
    log(f"done, {failures} failures")
    subprocess.run(["systemctl", "poweroff", "--no-block"])


if __name__ == "__main__":
    main()
