#!/usr/bin/python3
"""A renderer: connects to the daemon's socket as whoever runs it, subscribes to
snapshots, events and stats, and reads until `until` holds ("touches": a device
attached and a control or gesture event; "agents=N": a stats report with N agents;
"none": the time runs out). Prints one JSON summary line.

    client.py SOCKET SECONDS UNTIL
"""
import json
import socket
import sys
import time

path, seconds, until = sys.argv[1], float(sys.argv[2]), sys.argv[3]
out = {"connected": False, "snapshots": 0, "touch_events": 0, "attached": False, "agents": None}
try:
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.connect(path)
except OSError as e:
    out["error"] = f"{type(e).__name__}: {e}"
    print(json.dumps(out))
    sys.exit(0)
out["connected"] = True
s.sendall(b'{"type":"hello","protocol":1,"subscribe":["snapshot","events","stats"]}\n')
s.settimeout(0.5)
buf = b""
end = time.monotonic() + seconds
while time.monotonic() < end:
    try:
        chunk = s.recv(1 << 16)
    except socket.timeout:
        continue
    if not chunk:
        out["closed"] = True
        break
    buf += chunk
    *lines, buf = buf.split(b"\n")
    done = False
    for line in lines:
        try:
            v = json.loads(line)
        except ValueError:
            continue
        t = v.get("type")
        if t == "snapshot":
            out["snapshots"] += 1
        elif t in ("control", "gesture"):
            # What touches became: a control on the crowd or a gesture in open space
            # (raw touches are for privileged clients only).
            out["touch_events"] += 1
        elif t == "device" and v.get("state") == "attached":
            out["attached"] = True
            out["node"] = v.get("node")
        elif t == "stats":
            out["agents"] = v.get("agents")
        elif t == "hello":
            out["agents"] = v.get("agents")
        if until == "touches" and out["attached"] and out["touch_events"] > 0 and out["snapshots"] > 10:
            done = True
        if until.startswith("agents=") and out["agents"] == int(until.split("=")[1]):
            done = True
    if done:
        break
print(json.dumps(out))
