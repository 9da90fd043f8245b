#!/usr/bin/env node
// A stand-in for the daemon's WebSocket output, for working on the viewer page
// without it: serves src/publish/websocket/viewer.html at `/` (read from disk on
// every request, so a reload shows your edit) and bridges each WebSocket on `/ws`
// to its own connection to a running daemon's Unix socket, one JSON line per text
// message each way.
//
//   cargo run -- demo --agents 5000 --socket /tmp/ct.sock &
//   node tests/tools/viewer/bridge.js --socket /tmp/ct.sock --listen 127.0.0.1:8090
//   open http://127.0.0.1:8090/
//
// What it cannot do, because the Unix socket does not: touches from the page (the
// `touch` messages are counted and dropped: the socket would close the connection
// over an unknown type). `--read-only` answers every command with an `error` itself,
// to see how the page shows a read-only client's refusal; `--log-touches` prints
// every touch message the page sends.
//
// `--synthetic N` needs no daemon: it plays N agents walking in circles at 60
// snapshots a second, in the daemon's JSON (3 decimals), to measure what the page
// costs on its own:
//
//   node tests/tools/viewer/bridge.js --synthetic 5000 --listen 127.0.0.1:8090 &
//   node tests/tools/viewer/drive.js --fps http://127.0.0.1:8090/ 5

"use strict";
const fs = require("fs");
const http = require("http");
const net = require("net");
const path = require("path");
const { WebSocketServer } = require("ws");

function arg(name, fallback) {
  const i = process.argv.indexOf(name);
  return i > 0 && i + 1 < process.argv.length ? process.argv[i + 1] : fallback;
}
const socketPath = arg("--socket", `${process.env.XDG_RUNTIME_DIR || "/tmp"}/crowdtouch.sock`);
const [host, port] = arg("--listen", "127.0.0.1:8090").split(":");
const readOnly = process.argv.includes("--read-only");
const logTouches = process.argv.includes("--log-touches");
const synthetic = Number(arg("--synthetic", "0"));
const page = path.join(__dirname, "../../../src/publish/websocket/viewer.html");

const server = http.createServer((req, res) => {
  if (req.method === "GET" && (req.url === "/" || req.url.startsWith("/?"))) {
    res.writeHead(200, { "content-type": "text/html; charset=utf-8", "cache-control": "no-store" });
    res.end(fs.readFileSync(page));
  } else {
    res.writeHead(404, { "content-type": "text/plain" });
    res.end("not found\n");
  }
});

const wss = new WebSocketServer({ noServer: true });
server.on("upgrade", (req, sock, head) => {
  if (!req.url.startsWith("/ws")) return sock.destroy();
  wss.handleUpgrade(req, sock, head, (ws) => (synthetic > 0 ? play(ws, synthetic) : bridge(ws)));
});

let touchMessages = 0;

function bridge(ws) {
  const unix = net.createConnection(socketPath);
  let buf = "";
  unix.setEncoding("utf8");
  unix.on("data", (chunk) => {
    buf += chunk;
    let nl;
    while ((nl = buf.indexOf("\n")) >= 0) {
      const line = buf.slice(0, nl);
      buf = buf.slice(nl + 1);
      if (line && ws.readyState === ws.OPEN) ws.send(line);
    }
  });
  unix.on("error", (e) => ws.close(1011, `daemon socket ${socketPath}: ${e.code || e.message}`));
  unix.on("close", () => ws.close(1000));
  ws.on("message", (data) => {
    const text = data.toString("utf8");
    let msg = null;
    try { msg = JSON.parse(text); } catch (_) { /* the daemon says what is wrong */ }
    if (msg && msg.type === "touch") {
      if (logTouches) console.error(`bridge: touch ${JSON.stringify(msg.contacts)}`);
      if (++touchMessages % 100 === 1) console.error(`bridge: ${touchMessages} touch messages dropped (the Unix socket takes none)`);
      return;
    }
    if (readOnly && msg && msg.type === "command") {
      ws.send(JSON.stringify({ type: "error", id: msg.id ?? null,
        message: "read-only client: commands need a privileged connection (bridge --read-only)", fatal: false }));
      return;
    }
    unix.write(text + "\n");
  });
  ws.on("close", () => unix.end());
}

// The synthetic crowd: agents on a grid in the middle of a 16 x 9 m world, each
// circling its own place.
let clients = 0;
function play(ws, n) {
  const world = { min: [0.0, 0.0], max: [16.0, 9.0] };
  const hello = (rate) => JSON.stringify({
    type: "hello", protocol: 1, server: "bridge.js --synthetic", client: ++clients, formats: ["json"],
    format: "json", subscriptions: ["snapshot"], fields: ["positions"], max_rate_hz: rate, world,
    agents: n, agent_radius_m: 0.15, client_queue: 8, max_line_bytes: 65536,
  });
  ws.send(hello(null));
  ws.on("message", (data) => {
    let msg = null;
    try { msg = JSON.parse(data.toString("utf8")); } catch (_) { return; }
    if (msg.type === "hello") ws.send(hello(msg.max_rate_hz ?? null));
  });
  const cols = Math.ceil(Math.sqrt(n * 4 / 3)), spacing = 6 / cols;
  let seq = 0;
  const timer = setInterval(() => {
    seq++;
    const phase = seq / 60;
    const xy = new Array(2 * n);
    for (let i = 0; i < n; i++) {
      const cx = 5 + (i % cols) * spacing, cy = 2.5 + Math.floor(i / cols) * spacing;
      const a = phase + i * 0.37;
      xy[2 * i] = (cx + 0.3 * spacing * Math.cos(a)).toFixed(3);
      xy[2 * i + 1] = (cy + 0.3 * spacing * Math.sin(a)).toFixed(3);
    }
    const t_us = Math.round(performance.now() * 1000);
    if (ws.readyState === ws.OPEN && ws.bufferedAmount < 4 << 20) {
      ws.send(`{"type":"snapshot","seq":${seq},"t_us":${t_us},"latency_us":2000,"input_t_us":${t_us - 2000},` +
        `"dropped":0,"agents":${n},"paused":false,"positions":[${xy.join(",")}]}`);
    }
  }, 1000 / 60);
  ws.on("close", () => clearInterval(timer));
}

server.listen(Number(port), host, () => {
  const to = synthetic > 0 ? `${synthetic} synthetic agents` : socketPath;
  console.error(`bridge: http://${host}:${port}/ -> ${to}${readOnly ? " (read-only)" : ""}`);
});
