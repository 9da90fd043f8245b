#!/usr/bin/env python3
"""Load on a running crowdtouch daemon's socket, and what it costs the daemon.

Connects N clients that read the default stream (and discard it), optionally one more
that connects, reads the server's `hello` and closes, in a loop (churn); every second
prints the daemon's resident memory and thread count (/proc/PID/status, /proc/PID/task).
Standard library only.

    crowdtouch demo --socket /tmp/ct.sock &
    python3 benches/socket_load.py /tmp/ct.sock $(pgrep -n crowdtouch) 32 churn 20

Arguments: socket path, daemon pid, readers, `churn` or `no-churn`, seconds.
"""
import os
import selectors
import socket
import sys
import threading
import time


def status(pid):
    """(RSS in MB, threads) of process `pid`."""
    rss = 0.0
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                rss = int(line.split()[1]) / 1024
    return rss, len(os.listdir(f"/proc/{pid}/task"))


def main():
    path, pid, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    churn, secs = sys.argv[4] == "churn", float(sys.argv[5])
    print("idle: RSS %.1f MB, %d threads" % status(pid), flush=True)
    sel = selectors.DefaultSelector()
    for _ in range(n):
        s = socket.socket(socket.AF_UNIX)
        s.connect(path)
        s.setblocking(False)
        sel.register(s, selectors.EVENT_READ)
    cycles = [0]
    stop = threading.Event()

    def churner():
        while not stop.is_set():
            s = socket.socket(socket.AF_UNIX)
            s.connect(path)
            s.recv(4096)
            s.close()
            cycles[0] += 1

    if churn:
        threading.Thread(target=churner, daemon=True).start()
    t0 = last = time.time()
    peak, read = (0.0, 0), 0
    while time.time() - t0 < secs:
        for key, _ in sel.select(0.2):
            try:
                read += len(key.fileobj.recv(1 << 20))
            except BlockingIOError:
                pass
        if time.time() - last >= 1:
            last = time.time()
            st = status(pid)
            peak = max(peak, st)
            print("t=%.0fs RSS %.1f MB, %d threads, %d churn cycles, %.0f MB read"
                  % (last - t0, st[0], st[1], cycles[0], read / 1e6), flush=True)
    stop.set()
    print("peak RSS %.1f MB, peak threads %d, churn cycles %d (%.0f/s)"
          % (peak[0], peak[1], cycles[0], cycles[0] / secs))


if __name__ == "__main__":
    main()
