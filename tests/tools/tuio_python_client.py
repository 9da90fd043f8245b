#!/usr/bin/env python3
"""A TUIO 1.1 client written by others (python-tuio), for tests/tuio_output.rs.

Usage: tuio_python_client.py PORT SECONDS

Listens on 127.0.0.1:PORT for SECONDS, then prints one line
`RESULT {json}`: per kind (cursor, object, blob) how many sessions were added,
updated and removed, the most objects alive at once, every cursor's positions,
and the objects alive at the end with their positions. Prints `READY` once the
socket is bound. (python-tuio prints a line of its own for every bundle.)
"""
import json
import sys
import threading

from pythontuio import TuioClient
from pythontuio.dispatcher import TuioListener

port, seconds = int(sys.argv[1]), float(sys.argv[2])


class Recorder(TuioListener):
    def __init__(self, client):
        self.client = client
        self.counts = {k: {"add": 0, "update": 0, "remove": 0} for k in ("cursor", "object", "blob")}
        self.cursor_paths = {}
        self.max_objects = 0
        self.last_objects = []

    def add_tuio_cursor(self, c):
        self.counts["cursor"]["add"] += 1

    def update_tuio_cursor(self, c):
        self.counts["cursor"]["update"] += 1
        self.cursor_paths.setdefault(str(c.session_id), []).append(list(c.position))

    def remove_tuio_cursor(self, c):
        self.counts["cursor"]["remove"] += 1

    def add_tuio_object(self, o):
        self.counts["object"]["add"] += 1

    def update_tuio_object(self, o):
        self.counts["object"]["update"] += 1

    def remove_tuio_object(self, o):
        self.counts["object"]["remove"] += 1

    def add_tuio_blob(self, b):
        self.counts["blob"]["add"] += 1

    def update_tuio_blob(self, b):
        self.counts["blob"]["update"] += 1

    def remove_tuio_blob(self, b):
        self.counts["blob"]["remove"] += 1

    def refresh(self, time):
        alive = len(self.client.objects)
        if alive > 0:
            self.last_objects = [list(o.position) for o in self.client.objects]
        self.max_objects = max(self.max_objects, alive)


client = TuioClient(("127.0.0.1", port))
recorder = Recorder(client)
client.add_listener(recorder)


def ready_then_stop():
    print("READY", flush=True)
    threading.Timer(seconds, client.shutdown).start()


threading.Timer(0.2, ready_then_stop).start()
client.start()
print("RESULT " + json.dumps({
    "counts": recorder.counts,
    "max_objects": recorder.max_objects,
    "objects_alive_at_end": len(client.objects),
    "last_objects": recorder.last_objects,
    "cursor_paths": recorder.cursor_paths,
}), flush=True)
