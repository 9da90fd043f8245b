#!/usr/bin/env python3
"""A small crowdtouch client using only the Python standard library.

    python3 examples/client.py [--socket PATH] [--binary] [--rate HZ]
                               [--subscribe snapshot,events] [--fields positions,motions]
                               [--command pause]

Prints one line per message: a summary for snapshots (seq, agent count, latency,
drops, centroid, and how many agents do each motion when the daemon runs a scene),
the JSON for everything else. Protocol: docs/protocol.md.
"""

import argparse
import json
import os
import socket
import struct
import sys

# Binary snapshot header: everything after the u32 length (docs/protocol.md).
HEADER = struct.Struct("<BBHQQQQQIIII")  # kind, version, flags, seq, t_us, latency_us,
#                                          dropped, assignment_seq, agents, goals, touches, reserved
FLAG_POSITIONS, FLAG_VELOCITIES, FLAG_GOALS, FLAG_ASSIGNMENT, FLAG_TOUCHES = 1, 2, 4, 8, 16
FLAG_PAUSED, FLAG_LATENCY, FLAG_MOTIONS = 32, 64, 128
# Binary motion codes (docs/protocol.md, "Motions array"): the byte is the index.
MOTIONS = ("run", "crawl", "duck", "swim", "jump", "climb_up", "climb_down")


def default_socket():
    if "CROWDTOUCH_SOCKET" in os.environ:
        return os.environ["CROWDTOUCH_SOCKET"]
    if "XDG_RUNTIME_DIR" in os.environ:
        return os.path.join(os.environ["XDG_RUNTIME_DIR"], "crowdtouch.sock")
    if os.path.exists("/run/crowdtouch/crowdtouch.sock"):
        return "/run/crowdtouch/crowdtouch.sock"
    return "/tmp/crowdtouch-%d.sock" % os.getuid()


def read_exact(f, n):
    data = f.read(n)
    if len(data) < n:
        raise EOFError
    return data


def read_message(f, binary):
    """One message: ("json", dict) or ("snapshot", dict). Raises EOFError at the end."""
    if not binary:
        line = f.readline()
        if not line:
            raise EOFError
        return "json", json.loads(line)
    (length,) = struct.unpack("<I", read_exact(f, 4))
    body = read_exact(f, length)
    if body[0] == 1:  # a JSON message in a frame
        return "json", json.loads(body[1:])
    return "snapshot", decode_binary_snapshot(body)


def decode_binary_snapshot(body):
    """Decodes a binary snapshot frame body (the bytes after the u32 length)."""
    (kind, version, flags, seq, t_us, latency_us, dropped, assignment_seq,
     n, g, k, _reserved) = HEADER.unpack_from(body, 0)
    at = HEADER.size  # 60: arrays start 64 bytes into the frame
    snap = {"seq": seq, "t_us": t_us, "dropped": dropped, "agents": n,
            "assignment_seq": assignment_seq, "paused": bool(flags & FLAG_PAUSED),
            "latency_us": latency_us if flags & FLAG_LATENCY else None}
    for name, flag, count in (("positions", FLAG_POSITIONS, 2 * n),
                              ("velocities", FLAG_VELOCITIES, 2 * n),
                              ("goals", FLAG_GOALS, 2 * g)):
        if flags & flag:
            snap[name] = struct.unpack_from("<%df" % count, body, at)  # flat x0, y0, x1, y1, ...
            at += 4 * count
    if flags & FLAG_ASSIGNMENT:
        snap["assignment"] = struct.unpack_from("<%dI" % n, body, at)
        at += 4 * n
    if flags & FLAG_TOUCHES:
        touches = []
        for _ in range(k):
            tid, control, x, y = struct.unpack_from("<IIff", body, at)
            touches.append({"id": tid, "x": x, "y": y,
                            "control": None if control == 0xFFFFFFFF else control})
            at += 16
        snap["touches"] = touches
    if flags & FLAG_MOTIONS:
        # One byte per agent, then zero padding to a multiple of 4 (not read).
        # A code newer than this client is None: draw it with your default animation.
        snap["motions"] = [MOTIONS[c] if c < len(MOTIONS) else None for c in body[at:at + n]]
    return snap


def summarise(s):
    pos = s.get("positions") or []
    n = len(pos) // 2
    cx = sum(pos[0::2]) / n if n else 0.0
    cy = sum(pos[1::2]) / n if n else 0.0
    latency = "-" if s["latency_us"] is None else "%d us" % s["latency_us"]
    line = "snapshot seq=%d agents=%d latency=%s dropped=%d centroid=(%.3f, %.3f)" % (
        s["seq"], s["agents"], latency, s["dropped"], cx, cy)
    if s.get("motions"):
        counts = {}
        for m in s["motions"]:
            counts[m] = counts.get(m, 0) + 1
        line += " motions " + " ".join("%s=%d" % (m, c) for m, c in sorted(counts.items(), key=str))
    return line


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--socket", default=default_socket())
    p.add_argument("--binary", action="store_true", help="binary snapshots")
    p.add_argument("--rate", type=float, help="most snapshots per second")
    p.add_argument("--subscribe", help="comma list of snapshot,mesh,events,stats")
    p.add_argument("--fields", help="comma list of positions,velocities,goals,assignment,"
                   "touches,motions (binary clients get motions only when named)")
    p.add_argument("--command", help="send a command: reset, pause, resume")
    a = p.parse_args()

    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        sock.connect(a.socket)
    except OSError as e:
        sys.exit("%s: cannot connect: %s (is crowdtouch running?)" % (a.socket, e))
    f = sock.makefile("rb")

    # The server speaks first: its hello, as a JSON line.
    print(json.dumps(read_message(f, False)[1]))

    if a.binary or a.rate or a.subscribe or a.fields:
        hello = {"type": "hello", "protocol": 1,
                 "format": "binary" if a.binary else "json", "max_rate_hz": a.rate}
        if a.subscribe:
            hello["subscribe"] = a.subscribe.split(",")
        if a.fields:
            hello["fields"] = a.fields.split(",")
        sock.sendall((json.dumps(hello) + "\n").encode())
    if a.command:
        sock.sendall((json.dumps({"type": "command", "id": 1, "name": a.command}) + "\n").encode())

    binary = False
    try:
        while True:
            kind, msg = read_message(f, binary)
            if kind == "snapshot":
                print(summarise(msg))
            elif msg["type"] == "snapshot":
                print(summarise(msg))
            else:
                print(json.dumps(msg))
                if msg["type"] == "hello":
                    # Everything after the answer to our hello is in the new format.
                    binary = msg["format"] == "binary"
                if msg["type"] == "bye":
                    break
    except EOFError:
        print("connection closed")
    except KeyboardInterrupt:
        pass
    except BrokenPipeError:  # stdout closed (client.py | head): leave quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


if __name__ == "__main__":
    main()
