//! Formation transforms through the whole daemon, as a socket client sees them:
//! `set_formation` is acknowledged, a client subscribed to `transform` gets the
//! progress of the run prepared on the formation thread, then its summary and the
//! `formation` event; a client that did not subscribe gets none of the new
//! message types; a bad request is an `error` reply and the crowd goes on.

mod common;

use common::{daemon_on_channel, read_until};
use crowdtouch::config::Config;
use crowdtouch::pipeline::Daemon;
use crowdtouch::vocab::TouchFrame;
use serde_json::Value;
use std::io::{BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;

fn start(agents: u32, path: &Path) -> (Daemon, crossbeam_channel::Sender<TouchFrame>) {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = agents;
    cfg.pipeline.realtime = Default::default();
    daemon_on_channel(cfg, path, 16)
}

#[test]
fn a_client_sees_a_transform_run_end_and_the_formation_arrive() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let (daemon, _frames) = start(60, &path);
    let stream = UnixStream::connect(&path).unwrap();
    let mut w = stream.try_clone().unwrap();
    let mut r = BufReader::new(stream);
    writeln!(
        w,
        r#"{{"type":"hello","protocol":1,"subscribe":["events","transform"]}}"#
    )
    .unwrap();
    read_until(&mut r, 3.0, |v| v["type"] == "hello");
    // A second client with the default streams sees no transform messages.
    let mut plain = BufReader::new(UnixStream::connect(&path).unwrap());
    read_until(&mut plain, 3.0, |v| v["type"] == "hello");
    let plain = std::thread::spawn(move || {
        read_until(&mut plain, 20.0, |v| v["type"] == "formation")
            .into_iter()
            .filter_map(|v| v["type"].as_str().map(str::to_string))
            .collect::<Vec<_>>()
    });
    // Bad requests: an `error` reply each.
    let mut error_for = |command: &str| {
        writeln!(w, "{command}").unwrap();
        let msgs = read_until(&mut r, 3.0, |v| v["type"] == "error");
        msgs.last().unwrap().clone()
    };
    let e = error_for(r#"{"type":"command","id":1,"name":"set_formation","formation":"blob"}"#);
    assert_eq!(e["id"], 1);
    let m = e["message"].as_str().unwrap();
    assert!(m.contains("`blob`") && m.contains("arrow"), "{m}");
    let e = error_for(
        r#"{"type":"command","id":2,"name":"set_formation","formation":"line","method":"warp"}"#,
    );
    assert!(e["message"]
        .as_str()
        .unwrap()
        .contains("\"transform\" or \"mesh\""));
    let e = error_for(
        r#"{"type":"command","id":3,"name":"set_formation","formation":"line","duration":-1}"#,
    );
    assert!(e["message"].as_str().unwrap().contains("duration"));
    // The transform.
    writeln!(
        w,
        r#"{{"type":"command","id":4,"name":"set_formation","formation":"arrow","duration":3}}"#
    )
    .unwrap();
    let msgs = read_until(&mut r, 60.0, |v| v["type"] == "formation");
    let types: Vec<&str> = msgs.iter().filter_map(|v| v["type"].as_str()).collect();
    assert!(
        msgs.iter().any(|v| v["type"] == "ack" && v["id"] == 4),
        "{types:?}"
    );
    let progress: Vec<&Value> = msgs.iter().filter(|v| v["type"] == "transform").collect();
    assert!(progress.len() > 5, "{} transform messages", progress.len());
    assert!(progress.iter().all(|v| v["formation"] == "arrow"
        && v["method"] == "transform"
        && v["I_d"].is_number()
        && v["sigma_min_dis"].is_number()));
    assert_eq!(progress.last().unwrap()["progress"], 1.0);
    // Each agent's subgroup, one per agent, the same all through the run.
    let groups = &progress[0]["agent_subgroups"];
    let count = progress[0]["subgroups"].as_u64().unwrap();
    let ids: Vec<u64> = groups
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g.as_u64().unwrap())
        .collect();
    assert_eq!(ids.len(), 60);
    assert!(ids.iter().all(|&g| g < count), "{ids:?} of {count}");
    for g in 0..count {
        assert!(ids.contains(&g), "subgroup {g} has no agent: {ids:?}");
    }
    assert!(progress.iter().all(|v| &v["agent_subgroups"] == groups));
    let end = msgs
        .iter()
        .position(|v| v["type"] == "transform_end")
        .expect("a transform_end");
    let formation = msgs.iter().position(|v| v["type"] == "formation").unwrap();
    assert!(end < formation);
    assert_eq!(msgs[end]["outcome"], "arrived");
    assert_eq!(msgs[end]["agents"], 60);
    assert_eq!(msgs[formation]["name"], "arrow");
    let others = plain.join().unwrap();
    assert!(others.iter().any(|t| t == "formation"), "{others:?}");
    assert!(others.iter().any(|t| t == "snapshot"));
    assert!(others
        .iter()
        .all(|t| t != "transform" && t != "transform_end"));
    daemon.shutdown();
}
