//! The `outputs` section: where the crowd goes besides the Unix socket (which is
//! always there, `socket`). Each entry starts one output (ARCHITECTURE.md, "Adding
//! an output"): TUIO over UDP to a renderer, a WebSocket stream with the live viewer.
//!
//! ```ron
//! outputs: [
//!     Tuio(target: "127.0.0.1:3333", version: "1.1"),
//!     WebSocket(listen: "127.0.0.1:8080"),
//! ],
//! ```

use serde::{Deserialize, Serialize};
use std::net::{IpAddr, SocketAddr};

/// One output besides the Unix socket.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum OutputConfig {
    /// TUIO over OSC/UDP to one renderer (Unity, TouchDesigner, Processing, …).
    Tuio {
        /// Where the datagrams go, `host:port` (3333 is TUIO's usual port).
        target: String,
        /// TUIO version: `"1.1"` (`/tuio/2Dcur`, `/tuio/2Dobj`, `/tuio/2Dblb`) or
        /// `"2.0"` (`/tuio2/frm`, `ptr`, `tok`, `bnd`, `alv`).
        #[serde(default = "default_tuio_version")]
        version: String,
        /// What is sent: `Cursors` (the raw touches; needs `privileged`),
        /// `Objects` (agents), `Blobs` (controls, as their hull's box).
        #[serde(default = "default_tuio_profiles")]
        profiles: Vec<TuioProfile>,
        /// Frames per second at most (snapshots in between are skipped).
        #[serde(default = "default_tuio_rate_hz")]
        rate_hz: f64,
        /// Largest UDP datagram (bytes): a frame with more than fits is split
        /// into several bundles, each with its alive and fseq.
        #[serde(default = "default_tuio_max_datagram_bytes")]
        max_datagram_bytes: u32,
        /// The `source` name sent with every frame; `None`: `crowdtouch@<hostname>`.
        #[serde(default)]
        source: Option<String>,
        /// Whether this target may receive the raw touches (`Cursors`): raw
        /// coordinates can reveal what people type on a kiosk.
        #[serde(default)]
        privileged: bool,
    },
    /// A WebSocket server with the protocol v1 stream and the live viewer page.
    WebSocket {
        /// Address to listen on, `ip:port`. Anything but a loopback address needs
        /// a `token`.
        #[serde(default = "default_websocket_listen")]
        listen: String,
        /// A secret clients must present (`?token=` on the URL, or the
        /// `Authorization: Bearer` header); `None` only on a loopback address.
        #[serde(default)]
        token: Option<String>,
        /// Whether this output's clients are privileged: they receive the raw
        /// touches and may send commands and touches.
        #[serde(default)]
        privileged: bool,
        /// Most WebSocket clients at once.
        #[serde(default = "default_websocket_max_clients")]
        max_clients: u32,
        /// Largest message a client may send (bytes); larger closes the connection.
        #[serde(default = "default_websocket_max_message_bytes")]
        max_message_bytes: u32,
        /// Serve the live viewer page at `/`.
        #[serde(default = "default_true")]
        viewer: bool,
        /// Serve the newest `stats` as Prometheus text at `/metrics` (with the
        /// output's `token`, when it has one). Off unless asked for.
        #[serde(default)]
        metrics: bool,
        /// Web origins besides the server's own (`scheme://host[:port]`, like
        /// `"https://kiosk.example"`) whose pages may connect, read-only unless
        /// also in `privileged_origins`. A browser upgrade from any other origin is
        /// refused 403 (a page of any site can open `ws://127.0.0.1:…`).
        #[serde(default)]
        origins: Vec<String>,
        /// Web origins whose pages get the privilege of `privileged: true` clients
        /// (raw touches, commands), whatever `privileged` says.
        #[serde(default)]
        privileged_origins: Vec<String>,
        /// Host names (`name` or `name:port`) requests may name in their `Host`
        /// header besides the address they reached (and `localhost` on a loopback
        /// address); any other is refused 421, which defeats DNS rebinding.
        #[serde(default)]
        hosts: Vec<String>,
    },
}

/// What a TUIO output sends.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum TuioProfile {
    /// Touches: `/tuio/2Dcur` (1.1) or `ptr` (2.0).
    Cursors,
    /// Agents: `/tuio/2Dobj` (1.1) or `tok` (2.0).
    Objects,
    /// Controls, as their hull's box: `/tuio/2Dblb` (1.1) or `bnd` (2.0).
    Blobs,
}

/// The TUIO versions an output speaks.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum TuioVersion {
    /// TUIO 1.1.
    V1_1,
    /// TUIO 2.0.
    V2_0,
}

impl TuioVersion {
    /// The version a config string names.
    pub fn parse(s: &str) -> Option<TuioVersion> {
        match s {
            "1.1" | "1" => Some(TuioVersion::V1_1),
            "2.0" | "2" => Some(TuioVersion::V2_0),
            _ => None,
        }
    }
}

fn default_tuio_version() -> String {
    "1.1".to_string()
}

fn default_tuio_profiles() -> Vec<TuioProfile> {
    vec![TuioProfile::Objects, TuioProfile::Blobs]
}

fn default_tuio_rate_hz() -> f64 {
    60.0
}

/// A UDP payload that fits an Ethernet frame (1500 − 20 IP − 8 UDP).
fn default_tuio_max_datagram_bytes() -> u32 {
    1472
}

fn default_websocket_listen() -> String {
    "127.0.0.1:8080".to_string()
}

fn default_websocket_max_clients() -> u32 {
    16
}

fn default_websocket_max_message_bytes() -> u32 {
    64 * 1024
}

fn default_true() -> bool {
    true
}

/// Smallest datagram a TUIO frame is split into (bytes): a bundle with its
/// source, alive, one set and fseq.
pub const MIN_TUIO_DATAGRAM_BYTES: u32 = 512;
/// Largest UDP payload over IPv4.
pub const MAX_TUIO_DATAGRAM_BYTES: u32 = 65_507;

/// Whether `host:port` has a non-empty host and a port number (the host is
/// resolved when the output starts).
fn host_port(s: &str) -> bool {
    match s.rsplit_once(':') {
        Some((host, port)) => !host.is_empty() && port.parse::<u16>().is_ok_and(|p| p > 0),
        None => false,
    }
}

/// Range checks of `outputs`, as `(field path, message)`.
pub(super) fn validate_outputs(outputs: &[OutputConfig], p: &mut Vec<(String, String)>) {
    let mut check = |ok: bool, field: String, msg: String| {
        if !ok {
            p.push((field, msg));
        }
    };
    for (i, o) in outputs.iter().enumerate() {
        match o {
            OutputConfig::Tuio {
                target,
                version,
                profiles,
                rate_hz,
                max_datagram_bytes,
                source,
                privileged,
            } => {
                check(
                    host_port(target),
                    format!("outputs[{i}].target"),
                    format!("a TUIO target is host:port, like \"127.0.0.1:3333\", got {target:?}"),
                );
                check(
                    TuioVersion::parse(version).is_some(),
                    format!("outputs[{i}].version"),
                    format!("TUIO version must be \"1.1\" or \"2.0\", got {version:?}"),
                );
                check(
                    !profiles.is_empty(),
                    format!("outputs[{i}].profiles"),
                    "no profile: name at least one of Cursors, Objects, Blobs".to_string(),
                );
                check(
                    *privileged || !profiles.contains(&TuioProfile::Cursors),
                    format!("outputs[{i}].profiles"),
                    "Cursors sends the raw touches, which can reveal what people type: \
                     set privileged: true for this target, or leave Cursors out"
                        .to_string(),
                );
                check(
                    rate_hz.is_finite() && (1.0..=1000.0).contains(rate_hz),
                    format!("outputs[{i}].rate_hz"),
                    format!("TUIO rate must be 1 ..= 1000 Hz, got {rate_hz}"),
                );
                check(
                    (MIN_TUIO_DATAGRAM_BYTES..=MAX_TUIO_DATAGRAM_BYTES)
                        .contains(max_datagram_bytes),
                    format!("outputs[{i}].max_datagram_bytes"),
                    format!(
                        "datagram size must be {MIN_TUIO_DATAGRAM_BYTES} ..= \
                         {MAX_TUIO_DATAGRAM_BYTES} bytes, got {max_datagram_bytes}"
                    ),
                );
                if let Some(s) = source {
                    check(
                        !s.is_empty() && s.len() <= 128 && !s.chars().any(char::is_control),
                        format!("outputs[{i}].source"),
                        format!("source must be 1 ..= 128 printable characters, got {s:?}"),
                    );
                }
            }
            OutputConfig::WebSocket {
                listen,
                token,
                max_clients,
                max_message_bytes,
                origins,
                privileged_origins,
                hosts,
                ..
            } => {
                for (name, list) in [
                    ("origins", origins),
                    ("privileged_origins", privileged_origins),
                ] {
                    for (k, o) in list.iter().enumerate() {
                        if let Err(why) = normalize_origin(o) {
                            check(
                                false,
                                format!("outputs[{i}].{name}[{k}]"),
                                format!("{o:?}: {why}"),
                            );
                        }
                    }
                }
                for (k, h) in hosts.iter().enumerate() {
                    if let Err(why) = normalize_host(h) {
                        check(
                            false,
                            format!("outputs[{i}].hosts[{k}]"),
                            format!("{h:?}: {why}"),
                        );
                    }
                }
                let addr = listen.parse::<SocketAddr>();
                check(
                    addr.is_ok(),
                    format!("outputs[{i}].listen"),
                    format!(
                        "listen address must be ip:port, like \"127.0.0.1:8080\", got {listen:?}"
                    ),
                );
                let loopback = addr.as_ref().is_ok_and(|a| is_loopback(a.ip()));
                check(
                    addr.is_err() || loopback || token.is_some(),
                    format!("outputs[{i}].token"),
                    format!(
                        "{listen} is reachable from other machines: set a token clients \
                         must present, or listen on 127.0.0.1"
                    ),
                );
                if let Some(t) = token {
                    check(
                        t.len() >= 16 && t.chars().all(|c| c.is_ascii_graphic()),
                        format!("outputs[{i}].token"),
                        "a token must be at least 16 printable ASCII characters (no spaces)"
                            .to_string(),
                    );
                }
                check(
                    (1..=1024).contains(max_clients),
                    format!("outputs[{i}].max_clients"),
                    format!("max clients must be 1 ..= 1024, got {max_clients}"),
                );
                check(
                    (1024..=16 * 1024 * 1024).contains(max_message_bytes),
                    format!("outputs[{i}].max_message_bytes"),
                    format!("max message size must be 1 KiB ..= 16 MiB, got {max_message_bytes}"),
                );
            }
        }
    }
    let listens: Vec<&str> = outputs
        .iter()
        .filter_map(|o| match o {
            OutputConfig::WebSocket { listen, .. } => Some(listen.as_str()),
            _ => None,
        })
        .collect();
    for (k, l) in listens.iter().enumerate() {
        check(
            !listens[..k].contains(l),
            "outputs".to_string(),
            format!("two WebSocket outputs listen on {l}"),
        );
    }
}

/// A web origin as browsers send it in `Origin`: `scheme://host[:port]`, scheme
/// `http` or `https`, lowercase, without the scheme's default port (80, 443);
/// `Err` says what is wrong (a path, a query, user info, an empty host, a bad port).
pub fn normalize_origin(s: &str) -> Result<String, String> {
    let lower = s.to_ascii_lowercase();
    let (scheme, rest) = lower.split_once("://").ok_or_else(|| {
        "an origin is scheme://host[:port], like \"https://kiosk.example\"".to_string()
    })?;
    let default_port = match scheme {
        "http" => 80,
        "https" => 443,
        _ => return Err(format!("scheme {scheme:?} is not http or https")),
    };
    if rest.contains(['/', '?', '#', '@']) {
        return Err("an origin has no path, query, fragment or user info".to_string());
    }
    let (host, port) = split_host_port(rest)?;
    Ok(match port {
        Some(p) if p != default_port => format!("{scheme}://{host}:{p}"),
        _ => format!("{scheme}://{host}"),
    })
}

/// A `hosts` entry, lowercase: `name` or `name:port` (`[v6]` or `[v6]:port`).
pub fn normalize_host(s: &str) -> Result<String, String> {
    if s.contains(['/', '?', '#', '@']) || s.contains("://") {
        return Err("a host is name or name:port, without scheme or path".to_string());
    }
    let lower = s.to_ascii_lowercase();
    let (host, port) = split_host_port(&lower)?;
    Ok(match port {
        Some(p) => format!("{host}:{p}"),
        None => host.to_string(),
    })
}

/// `host[:port]` split, the host checked (letters, digits, `.`, `-`, `_`, or a
/// bracketed IPv6 address), the port 1..=65535.
fn split_host_port(s: &str) -> Result<(&str, Option<u16>), String> {
    let (host, port) = if let Some(v6) = s.strip_prefix('[') {
        let (addr, after) = v6
            .split_once(']')
            .ok_or_else(|| "an IPv6 host has its closing ]".to_string())?;
        addr.parse::<std::net::Ipv6Addr>()
            .map_err(|_| format!("[{addr}] is not an IPv6 address"))?;
        let port = match after {
            "" => None,
            p => Some(p.strip_prefix(':').ok_or("text after ]")?),
        };
        (&s[..addr.len() + 2], port)
    } else {
        match s.rsplit_once(':') {
            Some((h, p)) => (h, Some(p)),
            None => (s, None),
        }
    };
    let name_ok = host.starts_with('[')
        || (!host.is_empty()
            && host
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_')));
    if !name_ok {
        return Err(format!("host {host:?} is not a host name or address"));
    }
    let port = match port {
        None => None,
        Some(p) => Some(
            p.parse::<u16>()
                .ok()
                .filter(|&p| p > 0)
                .ok_or_else(|| format!("port {p:?} is not 1..=65535"))?,
        ),
    };
    Ok((host, port))
}

/// Whether `ip` only reaches this machine.
pub fn is_loopback(ip: IpAddr) -> bool {
    match ip {
        IpAddr::V4(v4) => v4.is_loopback(),
        IpAddr::V6(v6) => {
            v6.is_loopback() || v6.to_ipv4_mapped().is_some_and(|v4| v4.is_loopback())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problems(o: OutputConfig) -> Vec<(String, String)> {
        let mut p = Vec::new();
        validate_outputs(&[o], &mut p);
        p
    }

    fn tuio() -> OutputConfig {
        ron::from_str("Tuio(target: \"127.0.0.1:3333\")").expect("parses")
    }

    fn websocket(listen: &str, token: Option<&str>) -> OutputConfig {
        OutputConfig::WebSocket {
            listen: listen.to_string(),
            token: token.map(str::to_string),
            privileged: false,
            max_clients: 4,
            max_message_bytes: 65536,
            viewer: true,
            metrics: false,
            origins: vec![],
            privileged_origins: vec![],
            hosts: vec![],
        }
    }

    #[test]
    fn the_defaults_are_valid() {
        assert_eq!(problems(tuio()), vec![]);
        let ws: OutputConfig = ron::from_str("WebSocket()").expect("parses");
        assert_eq!(problems(ws), vec![]);
    }

    #[test]
    fn a_bad_target_version_or_rate_is_named() {
        let o: OutputConfig =
            ron::from_str("Tuio(target: \"nohost\", version: \"3\", rate_hz: 0.0)")
                .expect("parses");
        let fields: Vec<String> = problems(o).into_iter().map(|(f, _)| f).collect();
        assert_eq!(
            fields,
            vec![
                "outputs[0].target",
                "outputs[0].version",
                "outputs[0].rate_hz"
            ]
        );
    }

    #[test]
    fn raw_touches_need_a_privileged_target() {
        let o: OutputConfig =
            ron::from_str("Tuio(target: \"h:3333\", profiles: [Cursors])").expect("parses");
        let p = problems(o);
        assert_eq!(p.len(), 1);
        assert!(p[0].1.contains("privileged"), "{p:?}");
        let o: OutputConfig =
            ron::from_str("Tuio(target: \"h:3333\", profiles: [Cursors], privileged: true)")
                .expect("parses");
        assert_eq!(problems(o), vec![]);
    }

    #[test]
    fn a_websocket_beyond_loopback_needs_a_token() {
        assert_eq!(problems(websocket("127.0.0.1:8080", None)), vec![]);
        assert_eq!(problems(websocket("[::1]:8080", None)), vec![]);
        let p = problems(websocket("0.0.0.0:8080", None));
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].0, "outputs[0].token");
        assert_eq!(
            problems(websocket("0.0.0.0:8080", Some("0123456789abcdef"))),
            vec![]
        );
        let p = problems(websocket("0.0.0.0:8080", Some("short")));
        assert_eq!(p[0].0, "outputs[0].token");
    }

    #[test]
    fn origins_and_hosts_are_checked_and_named() {
        let o: OutputConfig = ron::from_str(
            "WebSocket(origins: [\"https://Kiosk.example:443\", \"http://x/path\"], \
             privileged_origins: [\"ftp://x\"], hosts: [\"kiosk.local:8080\", \"a b\"])",
        )
        .expect("parses");
        let fields: Vec<String> = problems(o).into_iter().map(|(f, _)| f).collect();
        assert_eq!(
            fields,
            vec![
                "outputs[0].origins[1]",
                "outputs[0].privileged_origins[0]",
                "outputs[0].hosts[1]"
            ]
        );
        assert_eq!(
            normalize_origin("https://Kiosk.example:443").as_deref(),
            Ok("https://kiosk.example")
        );
        assert_eq!(
            normalize_origin("http://[::1]:8080").as_deref(),
            Ok("http://[::1]:8080")
        );
        assert!(normalize_origin("http://x:0").is_err());
        assert!(normalize_origin("http://").is_err());
        assert!(normalize_origin("null").is_err());
        assert_eq!(normalize_host("Kiosk.Local").as_deref(), Ok("kiosk.local"));
        assert!(normalize_host("http://kiosk").is_err());
    }

    #[test]
    fn two_websockets_on_one_address_are_refused() {
        let mut p = Vec::new();
        validate_outputs(
            &[
                websocket("127.0.0.1:8080", None),
                websocket("127.0.0.1:8080", None),
            ],
            &mut p,
        );
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].0, "outputs");
    }
}
