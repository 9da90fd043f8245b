#!/usr/bin/env python3
"""The system test's host side: boots the Debian guest in QEMU with the test's disk,
listens for the TUIO datagrams the guest's service sends to the host (QEMU's user
network: the guest's 10.0.2.2 is this machine's loopback), collects the guest's
check lines from its second serial port, and says whether everything passed.

    host.py --kernel VMLINUZ --initrd INITRD --root ROOT.qcow2 --payload DISK.img
            --out DIR [--accel tcg|kvm] [--timeout S]

Writes DIR/results.json and DIR/console.log; exit 0 when every check passed and
the TUIO datagrams arrived, 1 otherwise. The QEMU process never outlives it.
"""
import argparse
import json
import os
import socket
import subprocess
import sys
import threading
import time


def main(argv):
    ap = argparse.ArgumentParser()
    for a in ("--kernel", "--initrd", "--root", "--payload", "--out"):
        ap.add_argument(a, required=True)
    ap.add_argument("--accel", default="tcg")
    ap.add_argument("--timeout", type=float, default=1500)
    args = ap.parse_args(argv)

    # The renderer on another host: what arrives on the port the guest targets.
    udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    udp.bind(("127.0.0.1", 0))
    udp.settimeout(0.5)
    port = udp.getsockname()[1]
    got = {"datagrams": 0, "bundles": 0, "bytes": 0, "first_s": None}
    stop = threading.Event()
    t0 = time.monotonic()

    def listen():
        while not stop.is_set():
            try:
                d, _ = udp.recvfrom(65536)
            except socket.timeout:
                continue
            got["datagrams"] += 1
            got["bytes"] += len(d)
            got["bundles"] += d.startswith(b"#bundle\x00")
            if got["first_s"] is None:
                got["first_s"] = round(time.monotonic() - t0, 1)

    th = threading.Thread(target=listen, daemon=True)
    th.start()

    results_path = os.path.join(args.out, "checks.jsonl")
    console = os.path.join(args.out, "console.log")
    cpu = ["-cpu", "host"] if args.accel == "kvm" else ["-cpu", "max"]
    cmd = ["qemu-system-x86_64", "-machine", f"q35,accel={args.accel}", *cpu, "-smp", "2", "-m", "1536",
           "-display", "none", "-no-reboot", "-monitor", "none",
           "-kernel", args.kernel, "-initrd", args.initrd,
           "-append", f"root=/dev/vda rw console=ttyS0 panic=-1 systemd.show_status=0 "
                      f"systest.tuio_port={port}",
           "-drive", f"file={args.root},format=qcow2,if=virtio",
           "-drive", f"file={args.payload},format=raw,if=virtio",
           "-netdev", "user,id=n0", "-device", "virtio-net-pci,netdev=n0",
           "-serial", f"file:{console}", "-serial", f"file:{results_path}"]
    with open(os.path.join(args.out, "qemu.cmdline"), "w") as f:
        f.write(" ".join(cmd) + "\n")
    print(f"systemd-test: booting the guest (TUIO listener on 127.0.0.1:{port})", flush=True)
    q = subprocess.Popen(cmd, stdin=subprocess.DEVNULL)
    with open(os.path.join(args.out, "qemu.pid"), "w") as f:
        f.write(f"{q.pid}\n")
    timed_out = False
    try:
        q.wait(timeout=args.timeout)
    except subprocess.TimeoutExpired:
        timed_out = True
        q.kill()
        q.wait()
    elapsed = time.monotonic() - t0
    os.unlink(os.path.join(args.out, "qemu.pid"))
    stop.set()
    th.join()

    checks, done = [], None
    if os.path.exists(results_path):
        for line in open(results_path, errors="replace"):
            line = line.strip()
            if not line.startswith("{"):
                continue
            try:
                v = json.loads(line)
            except ValueError:
                continue
            if "check" in v:
                checks.append(v)
            elif v.get("done"):
                done = v
    tuio_expected = any(c["check"] == "tuio_sent" for c in checks)
    checks.append({"check": "tuio_datagrams_reach_a_listener_outside_the_service",
                   "ok": got["bundles"] > 0 or not tuio_expected,
                   "detail": f"{got['datagrams']} datagrams ({got['bundles']} OSC bundles, {got['bytes']} bytes) "
                             f"on the host's 127.0.0.1:{port}, the guest's 10.0.2.2"})
    checks.append({"check": "the_guest_ran_every_check",
                   "ok": not timed_out and done is not None,
                   "detail": "timed out" if timed_out else (
                       f"finished in {done['t_s']} s" if done else f"stopped early (console: {console})")})
    ok = all(c["ok"] for c in checks) and len(checks) > 20
    for c in checks:
        print(f"{'ok  ' if c['ok'] else 'FAIL'} {c['check']}: {c.get('detail', '')[:200]}")
    passed = sum(c["ok"] for c in checks)
    print(f"systemd-test: {elapsed:.0f} s in QEMU")
    print(f"systemd-test: {passed} passed, {len(checks) - passed} failed")
    json.dump({"ok": ok, "seconds_in_qemu": round(elapsed, 1), "timed_out": timed_out,
               "checks": checks, "tuio": got}, open(os.path.join(args.out, "results.json"), "w"), indent=1)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
