#!/usr/bin/env python3
"""Reports for a HID touch digitizer, from its report descriptor alone.

An implementation of the HID report descriptor rules (HID 1.11 sections 6.2.2 and
6.2.2.7-8; usages from the Digitizer page, HUT chapter 16) written independently of
the daemon's parser, so the hardware-in-the-loop harness can feed a real device's
descriptor to the kernel (through uhid) and generate the input reports that device
would send, without trusting crowdtouch's own reading of the layout.

  hidgen.py describe FILE      the touch layout found, as JSON

Stdlib only.
"""
import json
import sys

# Usages (page << 16 | id).
TOUCH_SCREEN = 0x000D0004
TOUCH_PAD = 0x000D0005
FINGER = 0x000D0022
TIP_SWITCH = 0x000D0042
IN_RANGE = 0x000D0032
CONFIDENCE = 0x000D0047
CONTACT_ID = 0x000D0051
CONTACT_COUNT = 0x000D0054
CONTACT_COUNT_MAX = 0x000D0055
SCAN_TIME = 0x000D0056
PRESSURE = 0x000D0030
WIDTH = 0x000D0048
HEIGHT = 0x000D0049
X = 0x00010030
Y = 0x00010031


class Field:
    """One value in a report: where it is and what it means."""

    def __init__(self, kind, report_id, bit, size, usage, lmin, lmax, pmin, pmax, unit, unit_exp,
                 collections, constant):
        self.kind, self.report_id, self.bit, self.size = kind, report_id, bit, size
        self.usage, self.lmin, self.lmax = usage, lmin, lmax
        self.pmin, self.pmax, self.unit, self.unit_exp = pmin, pmax, unit, unit_exp
        self.collections = collections  # tuple of collection indices, outermost first
        self.constant = constant

    def json(self):
        return {"usage": f"0x{self.usage >> 16:04x}:0x{self.usage & 0xFFFF:04x}",
                "report_id": self.report_id, "bit_offset": self.bit, "bit_size": self.size,
                "logical": [self.lmin, self.lmax]}


def _signed(v, nbytes):
    bits = 8 * nbytes
    return v - (1 << bits) if nbytes and v & (1 << (bits - 1)) else v


class Descriptor:
    """The fields of every report a descriptor declares, and its collections."""

    def __init__(self, data):
        self.data = bytes(data)
        self.fields = []
        self.collections = []  # (usage, type, parent index)
        self.report_bits = {}  # (kind, report_id) -> bits after the id byte
        self._parse()

    def _parse(self):
        g = dict(page=0, lmin=0, lmax=0, pmin=0, pmax=0, unit=0, unit_exp=0, size=0, count=0, rid=0)
        stack = []
        usages, umin, umax = [], None, None
        open_cols = []
        d, i = self.data, 0
        while i < len(d):
            b = d[i]
            if b == 0xFE:  # long item: skipped whole
                if i + 2 >= len(d):
                    raise ValueError(f"byte {i}: truncated long item")
                i += 3 + d[i + 1]
                continue
            n = (0, 1, 2, 4)[b & 3]
            if i + 1 + n > len(d):
                raise ValueError(f"byte {i}: item 0x{b:02x} needs {n} data bytes, {len(d) - i - 1} left")
            raw = int.from_bytes(d[i + 1:i + 1 + n], "little")
            sval = _signed(raw, n)
            kind, tag = (b >> 2) & 3, b >> 4
            i += 1 + n
            if kind == 1:  # global
                if tag == 0: g["page"] = raw
                elif tag == 1: g["lmin"] = sval
                elif tag == 2: g["lmax"] = sval if g["lmin"] < 0 else raw
                elif tag == 3: g["pmin"] = sval
                elif tag == 4: g["pmax"] = sval if g["pmin"] < 0 else raw
                elif tag == 5: g["unit_exp"] = sval if sval < 8 else sval - 16 if n == 1 and raw < 16 else sval
                elif tag == 6: g["unit"] = raw
                elif tag == 7: g["size"] = raw
                elif tag == 8: g["rid"] = raw
                elif tag == 9: g["count"] = raw
                elif tag == 10: stack.append(dict(g))
                elif tag == 11:
                    if not stack:
                        raise ValueError(f"byte {i}: Pop without Push")
                    g = stack.pop()
            elif kind == 2:  # local
                full = raw if n == 4 else (g["page"] << 16) | raw
                if tag == 0: usages.append(full)
                elif tag == 1: umin = full
                elif tag == 2: umax = full
            elif kind == 0:  # main
                if tag == 10:  # collection
                    u = usages[0] if usages else (umin or 0)
                    self.collections.append((u, raw, open_cols[-1] if open_cols else None))
                    open_cols.append(len(self.collections) - 1)
                elif tag == 12:  # end collection
                    if not open_cols:
                        raise ValueError(f"byte {i}: End Collection without a collection")
                    open_cols.pop()
                elif tag in (8, 9, 11):
                    rkind = {8: "input", 9: "output", 11: "feature"}[tag]
                    key = (rkind, g["rid"])
                    bit = self.report_bits.get(key, 0)
                    constant = bool(raw & 1)
                    is_array = not (raw & 2)
                    lst = list(usages)
                    if umin is not None and umax is not None:
                        lst += list(range(umin, umax + 1))
                    for k in range(g["count"]):
                        if constant or not lst:
                            u = 0
                        elif is_array:
                            u = lst[0]  # an array item: its usages are the values
                        else:
                            u = lst[min(k, len(lst) - 1)]
                        self.fields.append(Field(rkind, g["rid"], bit, g["size"], u, g["lmin"], g["lmax"],
                                                 g["pmin"], g["pmax"], g["unit"], g["unit_exp"],
                                                 tuple(open_cols), constant))
                        bit += g["size"]
                    self.report_bits[key] = bit
                usages, umin, umax = [], None, None
            else:
                raise ValueError(f"byte {i - 1 - n}: reserved item type 3")

    def report_bytes(self, kind, rid):
        return (self.report_bits.get((kind, rid), 0) + 7) // 8 + (1 if rid else 0)

    def touch_collections(self):
        """Each touch application collection: its fingers and contact count fields."""
        out = []
        for ci, (u, ctype, parent) in enumerate(self.collections):
            if ctype != 1 or u not in (TOUCH_SCREEN, TOUCH_PAD):
                continue
            inside = [f for f in self.fields if ci in f.collections]
            fingers = {}
            for f in inside:
                if f.kind != "input" or f.constant:
                    continue
                # A finger is the innermost collection inside the application (its
                # usage is Finger on most devices, but some leave the usage out).
                inner = f.collections[-1]
                if inner != ci:
                    fingers.setdefault(inner, {})[f.usage] = f
            fingers = [v for _, v in sorted(fingers.items()) if X in v and Y in v and (TIP_SWITCH in v or CONTACT_ID in v)]
            count = next((f for f in inside if f.kind == "input" and f.usage == CONTACT_COUNT), None)
            cmax = next((f for f in inside if f.kind == "feature" and f.usage == CONTACT_COUNT_MAX), None)
            scan = next((f for f in inside if f.kind == "input" and f.usage == SCAN_TIME), None)
            if fingers:
                out.append(TouchLayout(self, u, fingers, count, cmax, scan))
        return out


class TouchLayout:
    def __init__(self, desc, usage, fingers, count, cmax, scan):
        self.desc, self.usage, self.fingers = desc, usage, fingers
        self.count, self.cmax, self.scan = count, cmax, scan
        self.report_id = fingers[0][X].report_id
        self.per_report = len(fingers)
        self.max_contacts = cmax.lmax if cmax and 0 < cmax.lmax < 256 else self.per_report

    def json(self):
        return {"application": "touchscreen" if self.usage == TOUCH_SCREEN else "touchpad",
                "report_id": self.report_id, "contacts_per_report": self.per_report,
                "max_contacts": self.max_contacts,
                "report_bytes": self.desc.report_bytes("input", self.report_id),
                "x": self.fingers[0][X].json(), "y": self.fingers[0][Y].json(),
                "contact_count": self.count.json() if self.count else None,
                "contact_count_maximum": self.cmax.json() if self.cmax else None,
                "finger_usages": sorted(f"0x{u:08x}" for u in self.fingers[0])}

    def x_range(self):
        f = self.fingers[0][X]
        return f.lmin, f.lmax

    def y_range(self):
        f = self.fingers[0][Y]
        return f.lmin, f.lmax

    def feature_replies(self):
        """(report id, bytes) for GET_FEATURE requests the kernel makes at probe."""
        if not self.cmax:
            return []
        rid = self.cmax.report_id
        b = bytearray(self.desc.report_bytes("feature", rid))
        if rid:
            b[0] = rid
        _put(b, self.cmax, self.max_contacts, 8 if rid else 0)
        return [(rid, bytes(b))]

    def reports(self, contacts, scan_time=0, per_report=None):
        """Input reports for one frame. `contacts`: list of (contact_id, x, y, tip) in
        logical units, lifting contacts (tip False) included as the spec asks. Splits
        the frame over several reports (hybrid mode) when it has more contacts than
        one report carries; the first report's Contact Count is the frame's total and
        the next ones carry 0."""
        if len(contacts) > self.max_contacts:
            raise ValueError(f"{len(contacts)} contacts, the device declares at most {self.max_contacts}")
        if len(contacts) > self.per_report and not self.count:
            raise ValueError("more contacts than one report carries and no Contact Count to chain reports")
        step = min(per_report or self.per_report, self.per_report)
        if step < len(contacts) and not self.count:
            raise ValueError("splitting a frame over reports needs a Contact Count field")
        chunks = [contacts[i:i + step] for i in range(0, max(len(contacts), 1), step)]
        out = []
        rid = self.report_id
        for k, chunk in enumerate(chunks):
            b = bytearray(self.desc.report_bytes("input", rid))
            off = 8 if rid else 0
            if rid:
                b[0] = rid
            for slot, fields in enumerate(self.fingers):
                if slot >= len(chunk):
                    continue
                cid, x, y, tip = chunk[slot]
                for u, f in fields.items():
                    if u == TIP_SWITCH: v = 1 if tip else 0
                    elif u == IN_RANGE: v = 1 if tip else 0
                    elif u == CONFIDENCE: v = 1
                    elif u == CONTACT_ID: v = cid
                    elif u == X: v = x
                    elif u == Y: v = y
                    elif u == PRESSURE: v = max(f.lmin, f.lmax // 2)
                    else: v = max(f.lmin, 0)
                    _put(b, f, v, off)
            if self.count:
                _put(b, self.count, len(contacts) if k == 0 else 0, off)
            if self.scan:
                _put(b, self.scan, scan_time & ((1 << self.scan.size) - 1), off)
            out.append(bytes(b))
        return out


def _put(buf, f, value, base):
    """Writes `value` into field `f` (little-endian bit order, HID 1.11 section 8.4)."""
    if f.lmin < 0:
        value &= (1 << f.size) - 1
    if value < 0 or value >= (1 << f.size):
        raise ValueError(f"value {value} does not fit {f.size} bits")
    bit = base + f.bit
    for k in range(f.size):
        byte, sh = divmod(bit + k, 8)
        if value >> k & 1:
            buf[byte] |= 1 << sh
        else:
            buf[byte] &= ~(1 << sh) & 0xFF


USAGE = """usage: hidgen.py describe FILE
       hidgen.py reports FILE FRAME [FRAME ...]
FRAME: contacts separated by commas, each ID:X:Y:TIP in logical units (TIP 1 or 0);
prints each frame's input reports as hex, one frame per line, reports separated by
spaces."""


def main(argv):
    if len(argv) >= 3 and argv[1] == "describe":
        d = Descriptor(open(argv[2], "rb").read())
        print(json.dumps([c.json() for c in d.touch_collections()], indent=1))
        return 0
    if len(argv) >= 4 and argv[1] == "reports":
        layout = Descriptor(open(argv[2], "rb").read()).touch_collections()[0]
        for k, frame in enumerate(argv[3:]):
            contacts = [tuple(int(v) for v in c.split(":")) for c in frame.split(",") if c]
            contacts = [(i, x, y, bool(t)) for i, x, y, t in contacts]
            print(" ".join(r.hex() for r in layout.reports(contacts, 100 * (k + 1))))
        return 0
    print(USAGE, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
