//! `crowdtouch bench e2e` with the renderers' outputs: the full daemon with a
//! WebSocket output read by clients and a TUIO output read over UDP.

use std::process::Command;

#[test]
fn bench_e2e_feeds_websocket_clients_and_a_tuio_reader() {
    let out = Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args([
            "bench",
            "e2e",
            "--agents",
            "300",
            "--seconds",
            "2",
            "--websocket-clients",
            "2",
            "--tuio",
            "--no-realtime",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = rows.as_array().unwrap();
    let row = |name: &str| {
        rows.iter()
            .find(|r| r["workload"] == name)
            .unwrap_or_else(|| panic!("no row {name}: {rows:?}"))
    };
    for name in [
        "websocket client 1 300 agents",
        "websocket client 2 300 agents",
    ] {
        let r = row(name);
        // A latency sample per snapshot read that carried a touch.
        assert!(r["samples"].as_u64().unwrap() > 0, "{r}");
        let note = r["note"].as_str().unwrap();
        assert!(!note.contains(": 0 snapshots"), "{note}");
    }
    let tuio = row("tuio 300 agents");
    assert!(tuio["samples"].as_u64().unwrap() > 0, "{tuio}");
    // Every datagram is a bundle with its frame number.
    assert!(
        tuio["note"].as_str().unwrap().contains("), 0 unreadable"),
        "{tuio}"
    );
}
