#!/usr/bin/env python3
"""A command flood against a running crowdtouch daemon (issue 14, item 8).

One client sends `pause` and `reset` alternately at 10,000 commands a second; a slow
reader subscribed to events reads 50 lines a second; a third client sends one
`resume` a second and waits for its reply. Prints, as JSON, what each saw: the flood's
commands sent and replies (how many `busy`, how many out of order), the slow reader's
lines and how its connection ended, the third client's acks, `busy` refusals, replies
meant for someone else, and round-trip times. Standard library only.

    crowdtouch demo --socket /tmp/ct.sock &
    python3 benches/socket_flood.py /tmp/ct.sock 15
"""
import json
import socket
import sys
import threading
import time


def connect(path, subscribe):
    """A connection after the hello exchange, asking for `subscribe`."""
    s = socket.socket(socket.AF_UNIX)
    s.connect(path)
    f = s.makefile("rb")
    f.readline()
    hello = {"type": "hello", "protocol": 1, "subscribe": subscribe}
    s.sendall((json.dumps(hello) + "\n").encode())
    while json.loads(f.readline())["type"] != "hello":
        pass
    return s, f


def main():
    path, secs = sys.argv[1], float(sys.argv[2])
    stop = threading.Event()
    res = {"flood_sent": 0, "flood_replies": 0, "flood_busy": 0, "flood_out_of_order": 0,
           "slow_lines": 0, "slow_state_events": 0, "slow_end": "open",
           "other_acks": 0, "other_busy": 0, "other_foreign": 0, "other_round_trip_ms": []}
    fs, ff = connect(path, [])

    def flood_replies():
        last = -1
        for line in ff:
            m = json.loads(line)
            if m.get("type") in ("ack", "error"):
                res["flood_replies"] += 1
                if str(m.get("message", "")).startswith("busy"):
                    res["flood_busy"] += 1
                if isinstance(m.get("id"), int):
                    res["flood_out_of_order"] += m["id"] <= last
                    last = m["id"]

    def flood():
        k, t0 = 0, time.time()
        while time.time() - t0 < secs:
            batch = "".join(json.dumps({"type": "command", "id": k + i,
                                        "name": "pause" if (k + i) % 2 == 0 else "reset"}) + "\n"
                            for i in range(100))
            try:
                fs.sendall(batch.encode())
            except OSError:
                break
            k += 100
            res["flood_sent"] = k
            time.sleep(max(0.0, t0 + k / 10000 - time.time()))

    ss, sf = connect(path, ["events"])

    def slow():
        try:
            while not stop.is_set():
                line = sf.readline()
                if not line:
                    res["slow_end"] = "closed by the daemon"
                    return
                res["slow_lines"] += 1
                m = json.loads(line)
                res["slow_state_events"] += m["type"] in ("paused", "reset")
                if m["type"] == "error":
                    res["slow_end"] = "error: " + m["message"]
                    return
                time.sleep(0.02)
        except OSError as e:
            res["slow_end"] = repr(e)

    for f in (flood_replies, flood, slow):
        threading.Thread(target=f, daemon=True).start()
    os_, of = connect(path, [])
    t0, k = time.time(), 0
    while time.time() - t0 < secs:
        k += 1
        t = time.time()
        os_.sendall((json.dumps({"type": "command", "id": "o%d" % k, "name": "resume"}) + "\n").encode())
        while True:
            m = json.loads(of.readline())
            if m.get("id") == "o%d" % k:
                break
            res["other_foreign"] += 1
        res["other_round_trip_ms"].append(round((time.time() - t) * 1000, 1))
        if m["type"] == "ack":
            res["other_acks"] += 1
        elif str(m.get("message", "")).startswith("busy"):
            res["other_busy"] += 1
        time.sleep(1)
    time.sleep(1)
    stop.set()
    print(json.dumps(res))


if __name__ == "__main__":
    main()
