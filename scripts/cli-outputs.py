#!/usr/bin/env python3
"""Record the outputs of crowdtouch's commands, and compare two recordings.

A fixed list of commands whose outputs are deterministic, run on the shipped
inputs (recordings, configs, scenes, formations, track files, the gesture
library, HID descriptors), every `--help`, and a few bad inputs. Two binaries
that behave alike give byte-identical directories.

Usage:
  scripts/cli-outputs.py run --bin PATH --out DIR [--only TEXT]
      Run every entry with the binary PATH; DIR must be missing or empty.
      For entry NAME it writes NAME.cmd (the command line), NAME.stdout,
      NAME.stderr, NAME.exit (exit status), NAME.files/ (every file the
      command wrote) and NAME.normalised (what was replaced, see below).
      --only runs the entries whose name contains TEXT (for debugging).
  scripts/cli-outputs.py compare DIR_A DIR_B
      Byte comparison of every file; prints each differing file with a short
      unified diff, then `N entries, M identical, K differ`. Exit 1 when an
      entry differs or exists on one side only.
      With --pictures-by-data, an SVG that differs in bytes is compared by
      what it draws instead (tests/pictures.rs, run over the two
      directories), and the size of a picture a command prints ("(N bytes)",
      "N bytes") is not compared when that entry's SVG differs: for a change
      that restyles pictures and must leave everything else as it was.
  scripts/cli-outputs.py list
      Print every entry with its command line.

Checking that a change to the command code changes no output:

  git worktree add /tmp/ct-before HEAD        # or the commit before the change
  (cd /tmp/ct-before && cargo build --release)
  cp /tmp/ct-before/target/release/crowdtouch /tmp/crowdtouch-before
  cargo build --release                        # the changed tree
  scripts/cli-outputs.py run --bin /tmp/crowdtouch-before --out /tmp/co-before
  scripts/cli-outputs.py run --bin target/release/crowdtouch --out /tmp/co-after
  scripts/cli-outputs.py compare /tmp/co-before /tmp/co-after

How entries run. Each entry runs in its own empty directory under a scratch
directory, with `repo` a symbolic link to this repository and `in` to inputs
made from shipped files at the start of the run, so every path a command sees
or prints is relative (`repo/config/...`, `in/...`, `out.svg`). argv[0] is
`crowdtouch` whatever the binary's file name (clap prints it in usage text).
The environment is fixed: HOME, XDG_RUNTIME_DIR, XDG_CONFIG_HOME,
XDG_STATE_HOME and TMPDIR point into the scratch directory (so no user or
system config is found and the socket path is private), TZ=UTC, COLUMNS=100,
no RUST_LOG, no CROWDTOUCH_CONFIG; stdin is /dev/null.

What is normalised (and nothing else; NAME.normalised counts each
replacement, so a change in how many there are shows as a difference):
  * everywhere: the scratch directory's absolute path -> <SCRATCH> (it
    shows in the socket path `check-config` prints, under XDG_RUNTIME_DIR),
    this repository's absolute path -> <REPO> (a safety net: entries pass
    relative paths), and the wall-clock timestamp that starts a log line,
    `[2026-01-02T03:04:05Z ` -> `[<TIME> ` (the gesture lines `replay`
    logs on stderr);
  * `transform`: the measured times `prepare_ms`, `step_us_p50`,
    `step_us_p99` (JSON), the `prepare` and `step time` lines (text);
  * `transform compare`: `prepare_ms` and `step_us_p99` (JSON; the text
    table shows no time).
Everything else is compared byte for byte: two runs of one binary, one
after the other or both at once on two cores, give identical directories.
Only `--help` of `demo`, `doctor`, `devices`, `bench` and `library
collect`, and `--help` and an error of `run`, `watch`, `record` and
`calibrate`: a live daemon, the machine's devices, a terminal or measured
times decide the rest of their output.
"""

import argparse
import difflib
import filecmp
import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# --------------------------------------------------------------------------
# Normalisation rules
# --------------------------------------------------------------------------


class Rule:
    """A regex replaced everywhere in an entry's text outputs."""

    def __init__(self, name, pattern, repl):
        self.name = name
        self.regex = re.compile(pattern, re.M)
        self.repl = repl


def json_keys(*keys):
    """The value of each JSON key (a number, null, or a flat object such as
    `{"mean": .., "ci95": .., "n": 1}`) replaced by "<normalised>"; the rest of
    the text keeps its bytes."""
    return [
        Rule(
            "json:%s" % k,
            r'("%s"\s*:\s*)(?:\{[^{}]*\}|-?[0-9][0-9.eE+-]*|null)' % re.escape(k),
            r'\1"<normalised>"',
        )
        for k in keys
    ]


LOG_TIME = Rule(
    "log-timestamp",
    r"^\[\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(?:\.\d+)?Z ",
    "[<TIME> ",
)

TRANSFORM_JSON = json_keys("prepare_ms", "step_us_p50", "step_us_p99")
TRANSFORM_TEXT = [
    Rule(
        "text:prepare",
        r"^(  prepare +)[0-9.]+ (?:µs|ms|s)\b",
        r"\1<N> ms",
    ),
    Rule(
        "text:step-time",
        r"^(  step time +p50 )[0-9.]+ (?:µs|ms), p99 [0-9.]+ (?:µs|ms)",
        r"\1<N> µs, p99 <N> µs",
    ),
]
TRANSFORM = TRANSFORM_JSON + TRANSFORM_TEXT
COMPARE = json_keys("prepare_ms", "step_us_p99")

# --------------------------------------------------------------------------
# Entries
# --------------------------------------------------------------------------


class Entry:
    def __init__(self, name, args, norm=(), needs=()):
        self.name = name
        self.args = list(args)
        self.norm = list(norm)
        # (entry name, path in its directory): copied into this entry's
        # directory before it runs (a file or a directory an earlier entry wrote).
        self.needs = list(needs)


F = "repo/tests/fixtures"
REC = "repo/config/recordings"
SCENES = "repo/config/scenes"
EDIT = "repo/docs/edit"
CFG = "repo/config/crowdtouch.ron"

RECORDINGS = [
    "01-point-drag",
    "02-line-drag",
    "03-line-pinch",
    "04-area-drag",
    "05-area-twist",
    "06-two-hands",
    "07-open-space-swipe",
]
SCENE_NAMES = [
    "corridor",
    "four_blocks",
    "multiple_paths",
    "obstacle_course",
    "single_block",
    "street",
    "woodland",
]
HID_DESCRIPTORS = [
    "3m_0596_0500.rdesc",
    "actionstar_2101_1011.rdesc",
    "actionstar_2101_1011.hid",
    "advanced_silicon_2575_0204.rdesc",
    "egalax_capacitive_0eef_7224.rdesc",
    "elan_04f3_010c.rdesc",
    "elan_04f3_0732.rdesc",
    "irtouch_6615_0070.rdesc",
    "ite_06cb_2968.rdesc",
    "lg_043e_9aa1.rdesc",
    "pqlabs_1ef1_0001.rdesc",
    "quanta_0408_3001.rdesc",
    "zytronic_14c8_0006.rdesc",
]
HID_LOGS = [
    "actionstar-2101-1011.inrange-sequence.hid",
    "goodix-27c6-0e30.lenovo-duet.touch-and-usi-pen.hid",
    "wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid",
]
# Recordings with their own device header, for `gesture classify`.
GESTURE_RECORDINGS = [
    F + "/atmel-maxtouch.1-finger-drag-up-down.events",
    F + "/atmel-maxtouch.2-fingers-touch-release.events",
    F + "/atmel-maxtouch.4-finger-drag-down.events",
    F + "/dell-canvas-27-touch.evemu",
    F + "/ite-8595-touchpad-06cb-2968.two-finger-scroll.yml",
    F + "/gestures/wacom-cintiq-13hd-touch-finger.flick.evemu",
    F + "/hid/wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid",
    F + "/hid/actionstar-2101-1011.inrange-sequence.hid",
    REC + "/07-open-space-swipe.jsonl",
    # header-less .events with their device description in front (made by make_inputs)
    "in/isdv4-double-center-circle.evemu",
    "in/isdv4-single-center-circle.evemu",
    "in/isdv4-double-center-scroll.evemu",
    "in/quanta-touch-hover.evemu",
    "in/bamboo-double-center-scroll.evemu",
]

# Every command and subcommand, for `--help` and `-h`.
COMMANDS = [
    [],
    ["run"],
    ["demo"],
    ["replay"],
    ["watch"],
    ["check-config"],
    ["doctor"],
    ["bench"],
    ["devices"],
    ["calibrate"],
    ["record"],
    ["hid"],
    ["hid", "describe"],
    ["scene"],
    ["scene", "check"],
    ["scene", "render"],
    ["formations"],
    ["transform"],
    ["transform", "compare"],
    ["edit"],
    ["edit", "check"],
    ["edit", "apply"],
    ["edit", "render"],
    ["edit", "path"],
    ["gesture"],
    ["gesture", "classify"],
    ["library"],
    ["library", "build"],
    ["library", "new"],
    ["library", "import-motion"],
    ["library", "remove"],
    ["library", "show"],
    ["library", "eval"],
    ["library", "add"],
    ["library", "collect"],
    ["library", "test-set"],
    ["synth-recordings"],
]


def entries():
    e = []
    add = lambda *a, **k: e.append(Entry(*a, **k))

    # ---- help, version, command-line errors (clap)
    for path in COMMANDS:
        stem = "-".join(path) or "top"
        add("help-" + stem, path + ["--help"])
        add("help-short-" + stem, path + ["-h"])
    add("help-subcommand-transform-compare", ["help", "transform", "compare"])
    add("version", ["--version"])
    add("usage-no-command", [])
    add("usage-unknown-command", ["frobnicate"])
    add("usage-missing-argument", ["transform", "--from", "square"])
    add("usage-bad-value", ["transform", "--from", "square", "--to", "arrow", "--cost", "cheapest"])
    add("usage-not-a-number", ["replay", REC + "/01-point-drag.jsonl", "--agents", "many"])

    # ---- check-config
    add("check-config-crowdtouch", ["check-config", CFG])
    add("check-config-kiosk", ["check-config", "repo/config/kiosk.ron"])
    add("check-config-no-device", ["check-config", "repo/config/no-device.ron"])
    add("check-config-doc-outputs", ["check-config", "in/doc-outputs.ron"])
    add("check-config-doc-tuio-input", ["check-config", "in/doc-tuio-input.ron"])
    add("check-config-scene", ["check-config", "in/scene.ron"])
    add("check-config-shapes", ["check-config", "in/shapes.ron"])
    add("check-config-error-syntax", ["check-config", "in/syntax.ron"])
    add("check-config-error-ranges", ["check-config", "in/ranges.ron"])
    add("check-config-error-unknown-field", ["check-config", "in/unknown-field.ron"])
    add("check-config-error-preflight", ["check-config", "in/preflight.ron"])
    add("check-config-error-missing", ["check-config", "in/missing.ron"])

    # ---- run, watch, record, calibrate: their errors only
    add("run-error-config", ["run", "--config", "in/ranges.ron"])
    add("run-error-missing-config", ["run", "--config", "in/missing.ron"])
    add("watch-error-no-socket", ["watch", "--socket", "nothing.sock", "--seconds", "1"])
    add("record-error-no-device", ["record", "--device", "/nonexistent/event99", "--seconds", "1", "-o", "r.evemu"])
    add("calibrate-error-no-device-input", ["calibrate", "--config", CFG])

    # ---- replay
    for r in RECORDINGS:
        add("replay-" + r, ["replay", "%s/%s.jsonl" % (REC, r), "--agents", "20", "--settle", "0.5"])
    add(
        "replay-05-area-twist-svg-tracks",
        ["replay", REC + "/05-area-twist.jsonl", "--agents", "20", "--settle", "0.5",
         "-o", "replay.jsonl", "--svg", "replay.svg", "--tracks", "tracks.jsonl", "--track-step", "0.2"],
    )
    add(
        "replay-07-open-space-swipe-svg",
        ["replay", REC + "/07-open-space-swipe.jsonl", "--agents", "30", "--settle", "1",
         "-o", "replay.jsonl", "--svg", "replay.svg"],
    )
    add(
        "replay-04-area-drag-scene-svg",
        ["replay", REC + "/04-area-drag.jsonl", "--config", "in/scene.ron", "--agents", "20",
         "--settle", "0.5", "-o", "replay.jsonl", "--svg", "replay.svg"],
    )
    add("replay-evemu", ["replay", F + "/dell-canvas-27-touch.evemu", "--agents", "20", "--settle", "0.5"])
    add("replay-hid-recorder", ["replay", F + "/hid/" + HID_LOGS[2], "--agents", "20", "--settle", "0.5"])
    add("replay-frames-jsonl", ["replay", REC + "/06-two-hands.jsonl", "--frames"])
    add("replay-frames-evemu", ["replay", F + "/dell-canvas-27-touch.evemu", "--frames"])
    add("replay-frames-libinput-yaml", ["replay", F + "/ite-8595-touchpad-06cb-2968.two-finger-scroll.yml", "--frames"])
    add("replay-frames-hid-recorder", ["replay", F + "/hid/" + HID_LOGS[0], "--frames"])
    add("replay-error-bad-line", ["replay", "in/bad-frame.jsonl", "--agents", "10", "--settle", "0"])
    add("replay-skip-bad-frames", ["replay", "in/bad-frame.jsonl", "--agents", "10", "--settle", "0", "--skip-bad-frames"])
    add("replay-error-missing", ["replay", "in/missing.jsonl"])
    add("replay-error-no-frame", ["replay", F + "/hid/" + HID_LOGS[1]])

    # ---- scene
    for s in SCENE_NAMES:
        add("scene-check-" + s, ["scene", "check", "%s/%s.ron" % (SCENES, s)])
    add("scene-check-radius-config", ["scene", "check", SCENES + "/corridor.ron", "--agent-radius-m", "0.3", "--config", "in/shapes.ron"])
    add("scene-check-error", ["scene", "check", "in/bad-scene.ron"])
    add("scene-check-error-missing", ["scene", "check", "in/missing.ron"])
    for s in SCENE_NAMES:
        add("scene-render-" + s, ["scene", "render", "%s/%s.ron" % (SCENES, s), "-o", s + ".svg"])
    add(
        "scene-render-street-options",
        ["scene", "render", SCENES + "/street.ron", "-o", "street.svg", "--goal", "2,4.5",
         "--agents", "12", "--t", "3.5", "--cell-m", "0.1"],
    )
    add("scene-render-error-goal", ["scene", "render", SCENES + "/corridor.ron", "-o", "x.svg", "--goal", "100,100"])
    add("scene-render-error-scene", ["scene", "render", "in/bad-scene.ron", "-o", "x.svg"])

    # ---- formations
    add("formations", ["formations", "--config", CFG])
    add("formations-svg", ["formations", "--config", CFG, "-o", "formations.svg"])
    add("formations-shapes-svg", ["formations", "--config", "in/shapes.ron", "-o", "formations.svg"])
    add("formations-error-config", ["formations", "--config", "in/ranges.ron"])

    # ---- transform
    t = lambda *a: ["transform"] + list(a)
    add("transform-square-arrow-json", t("--from", "square", "--to", "arrow", "--agents", "50", "--json"), norm=TRANSFORM)
    add("transform-square-arrow-text-svg", t("--from", "square", "--to", "arrow", "--agents", "50", "--svg", "transform.svg"), norm=TRANSFORM)
    add("transform-circle-ring-json", t("--from", "circle", "--to", "ring", "--agents", "60", "--json"), norm=TRANSFORM)
    add("transform-start-heart-json", t("--from", "start", "--to", "heart", "--agents", "40", "--json"), norm=TRANSFORM)
    add(
        "transform-line-two-groups-manhattan-json",
        t("--from", "line", "--to", "two_groups", "--agents", "30", "--cost", "manhattan", "--no-feedback", "--json"),
        norm=TRANSFORM,
    )
    add(
        "transform-column-wedge-euclidean-json",
        t("--from", "column", "--to", "wedge", "--agents", "30", "--cost", "euclidean", "--no-subgroups", "--seed", "3", "--json"),
        norm=TRANSFORM,
    )
    add(
        "transform-diamond-letter-a-paper-json",
        t("--from", "diamond", "--to", "letter_a", "--agents", "30", "--preset", "paper", "--subgroup-attraction", "dt", "--json"),
        norm=TRANSFORM,
    )
    add(
        "transform-files-json",
        t("--from", "repo/config/formations/letter_a.ron", "--to", "repo/config/formations/heart.png", "--agents", "40", "--json"),
        norm=TRANSFORM,
    )
    add("transform-config-shapes-text", t("--config", "in/shapes.ron", "--from", "star", "--to", "logo", "--agents", "30"), norm=TRANSFORM)
    add("transform-error-unknown-formation", t("--from", "square", "--to", "nosuch"))
    c = lambda *a: ["transform", "compare"] + list(a)
    add("transform-compare-text", c("--from", "square", "--to", "arrow", "--agents", "30"))
    add("transform-compare-json-svg", c("--from", "square", "--to", "arrow", "--agents", "30", "--json", "--svg", "compare.svg"), norm=COMPARE)
    add(
        "transform-compare-baselines",
        c("--from", "square", "--to", "arrow", "--agents", "30", "--variants", "orca,rvo,steering", "--timeout", "10"),
    )
    add("transform-compare-lambdas-svg", c("--from", "square", "--to", "ring", "--agents", "30", "--lambdas", "0,0.5,1", "--json", "--svg", "lambdas.svg"), norm=COMPARE)
    add("transform-compare-crossing-seeds", c("--from", "square", "--to", "arrow", "--agents", "30", "--scenario", "crossing", "--seeds", "2"))
    add("transform-compare-obstacles-paper", c("--from", "square", "--to", "arrow", "--agents", "30", "--scenario", "obstacles", "--preset", "paper"))
    add("transform-compare-path-json-svg", c("--from", "square", "--to", "arrow", "--agents", "30", "--scenario", "path", "--seeds", "2", "--json", "--svg", "path.svg"), norm=COMPARE)

    # ---- edit
    add("edit-check-crossing", ["edit", "check", EDIT + "/crossing.jsonl"])
    add("edit-check-crossing-json", ["edit", "check", EDIT + "/crossing.jsonl", "--json"])
    add("edit-check-corridor-group", ["edit", "check", EDIT + "/corridor-group.jsonl", "--threshold", "0.65"])
    add("edit-check-zara", ["edit", "check", F + "/crowd/crowds_zara01.txt", "--keep", "5"])
    add("edit-check-students-json", ["edit", "check", F + "/crowd/students001.txt", "--format", "eth", "--keep", "5", "--json"])
    add("edit-check-csv", ["edit", "check", "out.csv", "--threshold", "0.4"], needs=[("edit-apply-avoid-collisions-csv", "out.csv")])
    add("edit-check-error-bad-line", ["edit", "check", "in/bad-tracks.jsonl"])
    add("edit-check-error-format", ["edit", "check", "in/syntax.ron"])
    ops = {
        "a-drag": ["--ops", EDIT + "/a-drag.ron"],
        "b-drag-fixed": ["--ops", EDIT + "/b-drag-fixed.ron"],
        "c-retime": ["--ops", EDIT + "/c-retime.ron"],
        "g-turn": ["--ops", EDIT + "/g-turn.ron"],
        "doc-example": ["--ops", "in/doc-ops.ron"],
    }
    for k, v in ops.items():
        add("edit-apply-" + k, ["edit", "apply", EDIT + "/group.jsonl"] + v + ["-o", "out.jsonl"])
        add("edit-apply-" + k + "-json", ["edit", "apply", EDIT + "/group.jsonl"] + v + ["-o", "out.jsonl", "--json"])
    add("edit-apply-zara-json", ["edit", "apply", F + "/crowd/crowds_zara01.txt", "--ops", EDIT + "/f-zara.ron", "-o", "out.txt", "--json"])
    add("edit-apply-avoid-collisions-csv", ["edit", "apply", EDIT + "/crossing.jsonl", "--avoid-collisions", "--threshold", "0.4", "-o", "out.csv"])
    add("edit-apply-avoid-obstacles-json", ["edit", "apply", EDIT + "/corridor-group.jsonl", "--avoid-obstacles", "corridor", "-o", "out.jsonl", "--json"])
    add(
        "edit-apply-students-avoid-json",
        ["edit", "apply", F + "/crowd/students001.txt", "--format", "eth", "--avoid-collisions", "--threshold", "0.3", "-o", "out.jsonl", "--json"],
    )
    add("edit-apply-error-ops", ["edit", "apply", EDIT + "/group.jsonl", "--ops", "in/bad-ops.ron", "-o", "out.jsonl"])
    add("edit-apply-error-exists", ["edit", "apply", "group.jsonl", "--ops", EDIT + "/a-drag.ron", "-o", "group.jsonl"], needs=[("edit-path-group", "group.jsonl")])
    # The pictures of docs/motion-editing.md, as docs/edit/make-figures.sh draws them.
    r = lambda name, *a: add("edit-render-" + name, ["edit", "render"] + list(a) + ["-o", name + ".svg"])
    r("a-drag", EDIT + "/group.jsonl", "--ops", EDIT + "/a-drag.ron", "--title", "(a) a drag without fixed points (eq. 1)")
    r("b-drag-fixed", EDIT + "/group.jsonl", "--ops", EDIT + "/b-drag-fixed.ron", "--title", "(b) a drag with the ends fixed (eq. 6)")
    r("c-retime", EDIT + "/group.jsonl", "--ops", EDIT + "/c-retime.ron", "--at", "4")
    r("d-avoid-collisions", EDIT + "/crossing.jsonl", "--avoid-collisions", "--threshold", "0.4", "--at", "3.5")
    r("e-avoid-obstacles", EDIT + "/corridor-group.jsonl", "--avoid-obstacles", "corridor", "--at", "6")
    r("f-zara", F + "/crowd/crowds_zara01.txt", "--ops", EDIT + "/f-zara.ron")
    r("g-turn", EDIT + "/group.jsonl", "--ops", EDIT + "/g-turn.ron", "--at", "2", "--at", "5")
    p = lambda name, *a: add("edit-path-" + name, ["edit", "path"] + list(a))
    p("group", "--scene", "corridor", "--from", "1,2", "--to", "10,2", "--people", "9", "--step", "0.25", "-o", "group.jsonl")
    p("north", "--scene", "corridor", "--from", "5.5,0.2", "--to", "5.5,8.8", "--people", "9", "--step", "0.25", "-o", "north.jsonl")
    p("corridor-group", "--scene", "corridor", "--from", "5,4.5", "--to", "15.5,4.5", "--people", "25", "--step", "0.25", "-o", "corridor-group.jsonl")
    p("scene-file", "--scene", SCENES + "/single_block.ron", "--from", "1,4.5", "--to", "15,4.5", "--people", "6", "--spacing", "0.8", "--speed", "1.1", "-o", "block.jsonl")
    p("error-outside", "--scene", "corridor", "--from", "-5,2", "--to", "10,2", "--people", "9", "-o", "x.jsonl")

    # ---- gesture
    add("gesture-classify", ["gesture", "classify", "--config", CFG] + GESTURE_RECORDINGS)
    add("gesture-classify-json", ["gesture", "classify", "--config", CFG, "--json"] + GESTURE_RECORDINGS)
    add("gesture-classify-library", ["gesture", "classify", "--config", CFG, "--library", "small.ctgl"] + GESTURE_RECORDINGS[:4],
        needs=[("library-build-small", "small.ctgl")])
    add("gesture-classify-error-no-frame", ["gesture", "classify", "--config", CFG, F + "/hid/" + HID_LOGS[1]])
    add("gesture-classify-error-no-header", ["gesture", "classify", "--config", CFG, F + "/gestures/quanta-optical.touch-hover.events"])

    # ---- library
    add("library-show", ["library", "show"])
    add("library-show-file", ["library", "show", "--library", "repo/config/gestures/library.ctgl"])
    add("library-build-small", ["library", "build", "-o", "small.ctgl", "--motions-per-class", "1", "--gestures-per-motion", "2", "--classes", "translate,twist,contract"])
    add("library-build-style2", ["library", "build", "-o", "style2.ctgl", "--motions-per-class", "1", "--gestures-per-motion", "2", "--classes", "join,split", "--generator", "style2", "--seed", "7"])
    add("library-build-shipped", ["library", "build", "-o", "library.ctgl"])
    add("library-new", ["library", "new", "-o", "new.ctgl", "--class", "wave,circle", "--class", "spiral"])
    add("library-show-new", ["library", "show", "--library", "new.ctgl"], needs=[("library-new", "new.ctgl")])
    add("library-import-motion", ["library", "import-motion", EDIT + "/group.jsonl", "--class", "wave", "--library", "new.ctgl", "-o", "motion.ctgl"],
        needs=[("library-new", "new.ctgl")])
    add("library-import-motion-zara", ["library", "import-motion", F + "/crowd/crowds_zara01.txt", "--class", "stroll", "--library", "small.ctgl",
                                       "--duration-s", "4", "--seed", "3", "-o", "zara.ctgl"], needs=[("library-build-small", "small.ctgl")])
    add("library-add", ["library", "add", "--class", "twist", "--library", "small.ctgl", "-o", "added.ctgl", "--participant", "p1",
                        "in/isdv4-double-center-circle.evemu", "in/isdv4-single-center-circle.evemu"], needs=[("library-build-small", "small.ctgl")])
    add("library-add-second", ["library", "add", "--class", "translate", "--motion", "0", "--library", "added.ctgl", "-o", "added2.ctgl",
                               "--participant", "p2", "--device", "isdv4", "in/isdv4-double-center-scroll.evemu", REC + "/07-open-space-swipe.jsonl"],
        needs=[("library-add", "added.ctgl")])
    add("library-show-added", ["library", "show", "--library", "added2.ctgl"], needs=[("library-add-second", "added2.ctgl")])
    add("library-remove", ["library", "remove", "--class", "twist", "--library", "added.ctgl", "-o", "removed.ctgl"], needs=[("library-add", "added.ctgl")])
    add("library-test-set", ["library", "test-set", "test-set", "--per-class", "2"])
    add("library-test-set-style2", ["library", "test-set", "test-set", "--per-class", "1", "--generator", "style2", "--seed", "5"])
    add("library-eval", ["library", "eval"])
    add("library-eval-test", ["library", "eval", "--test", "test-set"], needs=[("library-test-set", "test-set")])
    add("library-eval-cross-style", ["library", "eval", "--cross-style", "--per-class", "5"])
    add("library-eval-cross-style-fit", ["library", "eval", "--cross-style", "--per-class", "5", "--fit", "--seed", "30"])
    add("library-eval-by-participant", ["library", "eval", "--library", "added2.ctgl", "--by", "participant"], needs=[("library-add-second", "added2.ctgl")])
    add("library-error-truncated", ["library", "show", "--library", "in/truncated.ctgl"])
    add("library-error-not-a-library", ["library", "show", "--library", CFG])

    # ---- hid
    for d in HID_DESCRIPTORS:
        add("hid-describe-" + d.replace("_", "-"), ["hid", "describe", F + "/hid/descriptors/" + d])
    for h in HID_LOGS:
        add("hid-describe-" + h.split(".")[0], ["hid", "describe", F + "/hid/" + h])
    add("hid-describe-not-a-descriptor", ["hid", "describe", CFG])
    add("hid-describe-error-missing", ["hid", "describe", "in/missing.rdesc"])

    # ---- synth-recordings
    add("synth-recordings", ["synth-recordings", "--out", "recordings"])
    return e


# --------------------------------------------------------------------------
# Inputs made from shipped files
# --------------------------------------------------------------------------


def read(rel):
    with open(os.path.join(REPO, rel), "rb") as f:
        return f.read()


def replace_once(text, old, new, what):
    if old not in text:
        raise SystemExit("cli-outputs: cannot make %s: %r is not in the shipped file" % (what, old))
    return text.replace(old, new, 1)


def make_inputs(indir):
    """Inputs the entries name as in/...: shipped configs with documented
    fragments spliced in, broken copies for the error entries, and
    header-less evemu recordings with their device descriptions in front."""
    os.makedirs(indir)

    def write(name, data):
        with open(os.path.join(indir, name), "wb" if isinstance(data, bytes) else "w") as f:
            f.write(data)

    cfg = read("config/crowdtouch.ron").decode()
    end = cfg.rstrip().rfind(")")
    # docs/install.md and docs/renderers.md: the output examples.
    write(
        "doc-outputs.ron",
        cfg[:end]
        + "    outputs: [\n"
        '        WebSocket(listen: "0.0.0.0:8080", token: Some("a-secret-of-16-or-more"), hosts: ["kiosk-7"], metrics: true),\n'
        '        Tuio(target: "127.0.0.1:3333", version: "2.0", profiles: [Objects, Blobs]),\n'
        '        Tuio(target: "127.0.0.1:3334", version: "1.1", profiles: [Cursors, Objects, Blobs],\n'
        "             privileged: true),\n"
        "    ],\n" + cfg[end:],
    )
    # docs/renderers.md: TUIO input.
    write(
        "doc-tuio-input.ron",
        replace_once(
            cfg,
            "    inputs: [\n",
            "    inputs: [\n"
            '        Tuio(listen: "0.0.0.0:3333", timeout_ms: 1000,\n'
            "             max_sessions_per_frame: 64, max_senders: 8, max_packets_per_s: 4000),\n",
            "doc-tuio-input.ron",
        ),
    )
    write("scene.ron", replace_once(cfg, "scene: None,", 'scene: Some("scenes/obstacle_course.ron"),', "scene.ron"))
    # The star of config/crowdtouch.ron's comment, and a bitmap shape.
    write(
        "shapes.ron",
        replace_once(
            cfg,
            "shapes: [],",
            "shapes: [\n"
            '            (name: "star", outline: [(1.0, 0.0), (0.2, 0.2), (0.0, 1.0), (-0.2, 0.2), (-1.0, 0.0), (-0.2, -0.2), (0.0, -1.0), (0.2, -0.2)]),\n'
            '            (name: "logo", bitmap: Some((path: "heart.png", c_min: (0, 0, 0), c_max: (90, 90, 90)))),\n'
            "        ],",
            "shapes.ron",
        ),
    )
    write("heart.png", read("config/formations/heart.png"))
    write("syntax.ron", "garbage(\n")
    bad = replace_once(cfg, "agents: 100,", "agents: 0,", "ranges.ron")
    bad = replace_once(bad, "cols: 10,", "cols: 1,", "ranges.ron")
    bad = replace_once(bad, "tick_hz: 120.0,", "tick_hz: -5.0,", "ranges.ron")
    write("ranges.ron", bad)
    write("unknown-field.ron", replace_once(cfg, "agents: 100,", 'agents: 100, colour: "red",', "unknown-field.ron"))
    pre = replace_once(cfg, "path: None,", 'path: Some("/nonexistent-dir/crowdtouch.sock"),', "preflight.ron")
    pre = replace_once(pre, '"recordings/02-line-drag.jsonl"', '"recordings/missing.jsonl"', "preflight.ron")
    write("preflight.ron", pre)

    scene = read("config/scenes/single_block.ron").decode()
    scene = replace_once(
        scene,
        "(11.5, 3.5), (13.5, 3.5), (13.5, 5.5), (11.5, 5.5)",
        "(11.5, 3.5), (13.5, 3.5), (12.5, 4.5), (13.5, 5.5), (11.5, 5.5)",
        "bad-scene.ron",
    )
    write("bad-scene.ron", scene)

    # docs/motion-editing.md: the edit script that shows every operation.
    write(
        "doc-ops.ron",
        "(\n    ops: [\n"
        "        Select(\n"
        "            ids: Some([1, 2, 3]),\n"
        "            rect: Some(((0.0, 0.0), (12.0, 9.0))),\n"
        "            lasso: Some([(0.0, 0.0), (6.0, 0.0), (3.0, 5.0)]),\n"
        "            time_s: Some((0.0, 30.0)),\n"
        "        ),\n"
        "        Fix(at: [(2.0, 5.0)]),\n"
        "        Unfix,\n"
        "        Drag(from: (4.0, 5.0), to: (4.5, 6.0), correct_speeds: true),\n"
        "        Retime(at_s: 12.0, to_s: 14.0, fixed_s: [0.0]),\n"
        "    ],\n)\n",
    )
    write("bad-ops.ron", "(\n    ops: [\n        Select(rect: Some(((0.0, 0.0), (12.0, 9.0)))),\n        Drag(from: (5.5, 2.0)),\n    ],\n)\n")

    lines = read("config/recordings/01-point-drag.jsonl").decode().splitlines(True)
    write("bad-frame.jsonl", "".join(lines[:40]) + '{"t_us": "soon", "contacts": [}\n' + "".join(lines[40:]))
    tracks = read("docs/edit/group.jsonl").decode().splitlines(True)
    write("bad-tracks.jsonl", "".join(tracks[:20]) + '{"id":1,"t_s":"later","x":1.0}\n' + "".join(tracks[20:]))
    write("truncated.ctgl", read("config/gestures/library.ctgl")[:4000])

    g = "tests/fixtures/gestures/"
    for name, desc, events in [
        ("isdv4-double-center-circle", "wacom-isdv4-e6-finger.desc", "wacom-isdv4-e6-finger.double-center-circle.events"),
        ("isdv4-single-center-circle", "wacom-isdv4-e6-finger.desc", "wacom-isdv4-e6-finger.single-center-circle.events"),
        ("isdv4-double-center-scroll", "wacom-isdv4-e6-finger.desc", "wacom-isdv4-e6-finger.double-center-scroll.events"),
        ("quanta-touch-hover", "quanta-optical.desc", "quanta-optical.touch-hover.events"),
        ("bamboo-double-center-scroll", "wacom-bamboo-16fg-4x5-finger.desc", "wacom-bamboo-16fg-4x5-finger.double-center-scroll.event"),
    ]:
        write(name + ".evemu", read(g + desc) + read(g + events))


# --------------------------------------------------------------------------
# run
# --------------------------------------------------------------------------


def file_hashes(root):
    """Regular files under root (not following symbolic links), by relative path."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if not os.path.islink(os.path.join(dirpath, d)))
        for fn in sorted(filenames):
            p = os.path.join(dirpath, fn)
            if os.path.islink(p) or not os.path.isfile(p):
                continue
            with open(p, "rb") as f:
                out[os.path.relpath(p, root)] = hashlib.sha256(f.read()).hexdigest()
    return out


def normalise(data, rules, counts, where):
    """Apply the rules to text (UTF-8) data; binary data is kept as it is."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        return data
    for rule in rules:
        text, n = rule.regex.subn(rule.repl, text)
        if n:
            counts.append("%s: %d in %s" % (rule.name, n, where))
    return text.encode("utf-8")


def quote(a):
    return a if re.fullmatch(r"[A-Za-z0-9_./,:=@%+-]+", a) else "'" + a.replace("'", "'\\''") + "'"


def ordered(todo):
    """The entries in list order, each moved after the entries it needs."""
    by_name = {e.name: e for e in todo}
    assert len(by_name) == len(todo), "entry names must be unique"
    done, out = set(), []

    def visit(e):
        if e.name in done:
            return
        done.add(e.name)
        for dep, _ in e.needs:
            visit(by_name[dep])
        out.append(e)

    for e in todo:
        visit(e)
    return out


def cmd_run(args):
    binary = os.path.abspath(args.bin)
    if not (os.path.isfile(binary) and os.access(binary, os.X_OK)):
        raise SystemExit("cli-outputs: %s is not an executable file" % args.bin)
    out = os.path.abspath(args.out)
    if os.path.exists(out) and os.listdir(out):
        raise SystemExit("cli-outputs: %s is not empty: give a new or empty directory" % args.out)
    os.makedirs(out, exist_ok=True)

    todo = ordered(entries())
    if args.only:
        wanted = {e.name for e in todo if args.only in e.name}
        # keep what they need
        for e in todo:
            if e.name in wanted:
                wanted.update(n for n, _ in e.needs)
        todo = [e for e in todo if e.name in wanted]

    scratch = tempfile.mkdtemp(prefix="cli-outputs-")
    started = time.monotonic()
    try:
        indir = os.path.join(scratch, "in")
        make_inputs(indir)
        env = {
            "PATH": os.environ.get("PATH", "/usr/bin:/bin"),
            "HOME": os.path.join(scratch, "home"),
            "XDG_RUNTIME_DIR": os.path.join(scratch, "run"),
            "XDG_CONFIG_HOME": os.path.join(scratch, "config"),
            "XDG_STATE_HOME": os.path.join(scratch, "state"),
            "TMPDIR": os.path.join(scratch, "tmp"),
            "TZ": "UTC",
            "LANG": "C.UTF-8",
            "COLUMNS": "100",
            "RUST_BACKTRACE": "0",
        }
        for d in ("home", "run", "config", "state", "tmp", "e"):
            os.makedirs(os.path.join(scratch, d), exist_ok=True)
        os.chmod(env["XDG_RUNTIME_DIR"], 0o700)
        global_rules = [
            Rule("scratch-path", re.escape(scratch), "<SCRATCH>"),
            Rule("repo-path", re.escape(REPO), "<REPO>"),
            LOG_TIME,
        ]
        slow = []
        for e in todo:
            cwd = os.path.join(scratch, "e", e.name)
            os.makedirs(cwd)
            os.symlink(REPO, os.path.join(cwd, "repo"))
            os.symlink(indir, os.path.join(cwd, "in"))
            setup_error = None
            for dep, rel in e.needs:
                src = os.path.join(scratch, "e", dep, rel)
                dst = os.path.join(cwd, rel)
                if os.path.isdir(src):
                    shutil.copytree(src, dst)
                elif os.path.isfile(src):
                    shutil.copyfile(src, dst)
                else:
                    setup_error = "setup: %s did not write %s\n" % (dep, rel)
            before = file_hashes(cwd)
            cmdline = "crowdtouch " + " ".join(quote(a) for a in e.args)
            t0 = time.monotonic()
            if setup_error:
                stdout, stderr, status = b"", setup_error.encode(), "setup-error"
            else:
                try:
                    p = subprocess.run(
                        ["crowdtouch"] + e.args,
                        executable=binary,
                        cwd=cwd,
                        env=env,
                        stdin=subprocess.DEVNULL,
                        stdout=subprocess.PIPE,
                        stderr=subprocess.PIPE,
                        timeout=args.timeout,
                    )
                    stdout, stderr = p.stdout, p.stderr
                    status = str(p.returncode)
                except subprocess.TimeoutExpired as t:
                    stdout, stderr = t.stdout or b"", t.stderr or b""
                    status = "timeout after %d s" % args.timeout
            took = time.monotonic() - t0
            slow.append((took, e.name))

            rules = global_rules + e.norm
            counts = []
            base = os.path.join(out, e.name)
            with open(base + ".cmd", "w") as f:
                f.write(cmdline + "\n")
            with open(base + ".stdout", "wb") as f:
                f.write(normalise(stdout, rules, counts, "stdout"))
            with open(base + ".stderr", "wb") as f:
                f.write(normalise(stderr, rules, counts, "stderr"))
            with open(base + ".exit", "w") as f:
                f.write(status + "\n")
            after = file_hashes(cwd)
            for rel in sorted(after):
                if before.get(rel) == after[rel]:
                    continue
                dst = os.path.join(base + ".files", rel)
                os.makedirs(os.path.dirname(dst), exist_ok=True)
                with open(os.path.join(cwd, rel), "rb") as f:
                    data = f.read()
                with open(dst, "wb") as f:
                    f.write(normalise(data, rules, counts, "files/" + rel))
            with open(base + ".normalised", "w") as f:
                f.write("".join(c + "\n" for c in counts))
            if args.verbose:
                print("%6.2f s  %-4s %s" % (took, status, e.name), file=sys.stderr)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    wall = time.monotonic() - started
    slow.sort(reverse=True)
    print("%d entries in %.1f s -> %s" % (len(todo), wall, args.out))
    print("slowest: " + ", ".join("%s %.1f s" % (n, t) for t, n in slow[:5]))
    return 0


# --------------------------------------------------------------------------
# compare
# --------------------------------------------------------------------------

SUFFIXES = (".cmd", ".stdout", ".stderr", ".exit", ".normalised")


def entry_files(root):
    """{entry: {relative path: absolute path}} of a run directory."""
    found = {}
    names = sorted(fn[: -len(".exit")] for fn in os.listdir(root) if fn.endswith(".exit"))
    for n in names:
        files = {}
        for s in SUFFIXES:
            p = os.path.join(root, n + s)
            if os.path.isfile(p):
                files[n + s] = p
        fdir = os.path.join(root, n + ".files")
        if os.path.isdir(fdir):
            for rel in file_hashes(fdir):
                files[os.path.join(n + ".files", rel)] = os.path.join(fdir, rel)
        found[n] = files
    claimed = {rel for files in found.values() for rel in files}
    other = {}
    for rel in file_hashes(root):
        if rel not in claimed:
            other[rel] = os.path.join(root, rel)
    if other:
        found["(files of no entry)"] = other
    return found


def clip(line, width=200):
    line = line.rstrip("\n")
    return line if len(line) <= width else line[:width] + " …(%d chars)" % len(line)


def show_difference(rel, a, b, max_lines):
    with open(a, "rb") as f:
        da = f.read()
    with open(b, "rb") as f:
        db = f.read()
    if da == db:
        return False
    print("--- differs: %s" % rel)
    try:
        ta, tb = da.decode("utf-8"), db.decode("utf-8")
    except UnicodeDecodeError:
        k = next((i for i in range(min(len(da), len(db))) if da[i] != db[i]), min(len(da), len(db)))
        print("    binary: %d and %d bytes, first difference at byte %d" % (len(da), len(db), k))
        return True
    la, lb = ta.splitlines(True), tb.splitlines(True)
    for i in range(min(len(la), len(lb))):
        if la[i] != lb[i]:
            col = next((j for j in range(min(len(la[i]), len(lb[i]))) if la[i][j] != lb[i][j]), min(len(la[i]), len(lb[i])))
            print("    first difference: line %d, column %d" % (i + 1, col + 1))
            if len(la[i]) > 200 or len(lb[i]) > 200:
                lo = max(0, col - 60)
                print("    A: …%s…" % la[i][lo : col + 80].rstrip("\n"))
                print("    B: …%s…" % lb[i][lo : col + 80].rstrip("\n"))
            break
    else:
        print("    first difference: line %d (one side ends)" % (min(len(la), len(lb)) + 1))
    diff = difflib.unified_diff(la, lb, "A/" + rel, "B/" + rel, n=2)
    for k, line in enumerate(diff):
        if k >= max_lines:
            print("    … (diff cut at %d lines)" % max_lines)
            break
        print("    " + clip(line))
    return True


PICTURE_SIZE = re.compile(rb"\b\d+ bytes\b")


def same_but_picture_size(a, b):
    """Whether two files are the same once every "N bytes" is blanked."""
    with open(a, "rb") as f:
        da = f.read()
    with open(b, "rb") as f:
        db = f.read()
    return PICTURE_SIZE.sub(b"<N> bytes", da) == PICTURE_SIZE.sub(b"<N> bytes", db)


def pictures_by_data(a, b):
    """Runs the folder comparison of tests/pictures.rs over two run directories."""
    env = dict(os.environ, CROWDTOUCH_PICTURES_BEFORE=os.path.abspath(a), CROWDTOUCH_PICTURES_AFTER=os.path.abspath(b))
    cmd = ["cargo", "test", "--release", "--quiet", "--test", "pictures", "--",
           "--ignored", "--nocapture", "pictures_in_two_folders_show_the_same_data"]
    print("pictures by what they draw: %s" % " ".join(cmd))
    run = subprocess.run(cmd, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    for line in run.stdout.splitlines():
        if "same data" in line or "DIFFERS" in line or "MISSING" in line or "pictures:" in line or "only" in line:
            print("    " + clip(line))
    return run.returncode == 0


def cmd_compare(args):
    for d in (args.a, args.b):
        if not os.path.isdir(d):
            raise SystemExit("cli-outputs: %s is not a directory" % d)
    ea, eb = entry_files(args.a), entry_files(args.b)
    names = sorted(set(ea) | set(eb))
    identical = differ = 0
    missing = []
    pictures, sized = [], []
    for n in names:
        if n not in ea or n not in eb:
            side, files = (args.a, ea[n]) if n in ea else (args.b, eb[n])
            missing.append("%s: only in %s (%s)" % (n, side, ", ".join(sorted(files))))
            differ += 1
            continue
        fa, fb = ea[n], eb[n]
        same = True
        rels = sorted(set(fa) | set(fb))
        restyled = args.pictures_by_data and any(
            r.endswith(".svg") and r in fa and r in fb and not filecmp.cmp(fa[r], fb[r], shallow=False) for r in rels
        )
        for rel in rels:
            if rel not in fa or rel not in fb:
                print("--- only in %s: %s" % (args.a if rel in fa else args.b, rel))
                same = False
            elif restyled and rel.endswith(".svg"):
                pictures.append(rel)
            elif restyled and not filecmp.cmp(fa[rel], fb[rel], shallow=False) and same_but_picture_size(fa[rel], fb[rel]):
                sized.append(rel)
            elif show_difference(rel, fa[rel], fb[rel], args.max_lines):
                same = False
        if same:
            identical += 1
        else:
            differ += 1
    for m in missing:
        print("--- entry %s" % m)
    print("%d entries, %d identical, %d differ" % (len(names), identical, differ))
    if args.pictures_by_data:
        print("%d pictures differ in bytes (compared by what they draw below); %d outputs differ only in "
              "the size of their picture" % (len(pictures), len(sized)))
        if pictures and not pictures_by_data(args.a, args.b):
            print("pictures: some no longer show the same data")
            return 1
    return 1 if differ else 0


def cmd_list(_args):
    for e in ordered(entries()):
        extra = ""
        if e.norm:
            extra += "  [normalised: %s]" % ", ".join(sorted({r.name for r in e.norm}))
        if e.needs:
            extra += "  [needs: %s]" % ", ".join("%s/%s" % n for n in e.needs)
        print("%-48s crowdtouch %s%s" % (e.name, " ".join(quote(a) for a in e.args), extra))
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run every entry with a binary into a directory")
    r.add_argument("--bin", required=True, help="the crowdtouch binary")
    r.add_argument("--out", required=True, help="output directory (missing or empty)")
    r.add_argument("--only", help="only the entries whose name contains this (and what they need)")
    r.add_argument("--timeout", type=int, default=120, help="seconds an entry may take (default 120)")
    r.add_argument("-v", "--verbose", action="store_true", help="print each entry's time and status")
    c = sub.add_parser("compare", help="compare two run directories")
    c.add_argument("a", metavar="DIR_A")
    c.add_argument("b", metavar="DIR_B")
    c.add_argument("--max-lines", type=int, default=20, help="diff lines shown per file (default 20)")
    c.add_argument("--pictures-by-data", action="store_true",
                   help="compare SVGs by what they draw (tests/pictures.rs), not their bytes")
    sub.add_parser("list", help="print the entries")
    args = ap.parse_args()
    return {"run": cmd_run, "compare": cmd_compare, "list": cmd_list}[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
