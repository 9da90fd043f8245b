//! Where a config's touches come from: its touch devices, recordings and TUIO
//! inputs, and the clients that may send `touch` commands. `check-config`, `run`
//! and `doctor` say it in the same words when no touch device is configured.
//!
//! Every config has a way in. The Unix socket is always served (`socket`; no
//! config turns it off), and its privileged clients — root, the daemon's own user,
//! the users and groups of `socket.privileged` — may send `touch`
//! (docs/protocol.md), which the control thread makes into frames of a virtual
//! surface per client (`client_touch.rs`). So a config without inputs is not a
//! mistake but a table touched only by clients: a kiosk whose touches come from
//! the viewer page over a WebSocket output, from TUIO senders, or from a program
//! on the same machine. It starts like any other, and no device is looked for:
//! discovery and the hotplug watch run only on the thread of a `Device` input.
//!
//! What counts as a way in, besides the socket:
//! * a `Device` input (a touch device), a `Replay` input (recordings), a `Tuio`
//!   input (TUIO senders on its port);
//! * a `WebSocket` output whose clients may send commands: `privileged: true`
//!   (its viewer page's mouse and fingers, and any client with its token), or
//!   listing `privileged_origins` (the pages of those origins). One with
//!   `privileged: false` serves the viewer, but the page cannot touch; that is
//!   said too.

use crate::config::{Config, InputConfig, OutputConfig};

/// The ways touches reach a config's crowd.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TouchSources {
    /// Indices (in `inputs`) of the `Device` inputs.
    pub devices: Vec<usize>,
    /// Indices of the `Replay` inputs.
    pub recordings: Vec<usize>,
    /// The listen address of each `Tuio` input.
    pub tuio: Vec<String>,
    /// The `WebSocket` outputs.
    pub websockets: Vec<WebSocketTouch>,
}

/// A `WebSocket` output, as a way in.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WebSocketTouch {
    /// Its listen address.
    pub listen: String,
    /// Its clients may send commands, `touch` among them (`privileged`).
    pub privileged: bool,
    /// Pages of these origins may (`privileged_origins`).
    pub privileged_origins: usize,
    /// It serves the viewer page (`viewer`).
    pub viewer: bool,
}

impl WebSocketTouch {
    /// Whether some client of this output may send `touch`.
    pub fn touches(&self) -> bool {
        self.privileged || self.privileged_origins > 0
    }
}

impl TouchSources {
    /// The ways in of `cfg`.
    pub fn of(cfg: &Config) -> TouchSources {
        let mut out = TouchSources::default();
        for (i, input) in cfg.inputs.iter().enumerate() {
            match input {
                InputConfig::Device { .. } => out.devices.push(i),
                InputConfig::Replay { .. } => out.recordings.push(i),
                InputConfig::Tuio { listen, .. } => out.tuio.push(listen.clone()),
            }
        }
        for o in &cfg.outputs {
            if let OutputConfig::WebSocket {
                listen,
                privileged,
                privileged_origins,
                viewer,
                ..
            } = o
            {
                out.websockets.push(WebSocketTouch {
                    listen: listen.clone(),
                    privileged: *privileged,
                    privileged_origins: privileged_origins.len(),
                    viewer: *viewer,
                });
            }
        }
        out
    }

    /// Whether a touch device is configured (a `Device` input).
    pub fn has_device(&self) -> bool {
        !self.devices.is_empty()
    }

    /// The clients that may touch, in words, the Unix socket's last: one entry
    /// per way in (never empty: the socket is always served).
    pub fn clients(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .tuio
            .iter()
            .map(|l| format!("TUIO senders to {l}"))
            .collect();
        for w in self.websockets.iter().filter(|w| w.touches()) {
            let who = match (w.privileged, w.viewer) {
                (true, true) => "the viewer page and the WebSocket clients",
                (true, false) => "the WebSocket clients",
                (false, _) => "the pages of its privileged_origins",
            };
            out.push(format!("{who} of http://{}/ (`touch` command)", w.listen));
        }
        out.push(
            "privileged clients of the Unix socket (`touch` command: root, the daemon's user, \
             socket.privileged)"
                .to_string(),
        );
        out
    }

    /// One line saying that no touch device is configured and where touches come
    /// from instead; `None` when a `Device` input is configured. The words of
    /// `check-config`, `run`'s log and `doctor`.
    pub fn without_device(&self) -> Option<String> {
        if self.has_device() {
            return None;
        }
        let clients = self.clients().join(", ");
        let mut line = if self.recordings.is_empty() {
            format!("no touch device configured: touches come only from clients: {clients}")
        } else {
            let inputs: Vec<String> = self
                .recordings
                .iter()
                .map(|i| format!("inputs[{i}]"))
                .collect();
            format!(
                "no touch device configured: touches come from the recordings of {} and from \
                 clients: {clients}",
                inputs.join(", ")
            )
        };
        for w in self.websockets.iter().filter(|w| !w.privileged && w.viewer) {
            line.push_str(&format!(
                "; the viewer of http://{}/ is read-only and cannot touch (privileged: true \
                 lets it)",
                w.listen
            ));
        }
        Some(line)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DEFAULT_CONFIG_RON;
    use std::path::Path;

    fn config(inputs: &str, outputs: &str) -> Config {
        let mut c = Config::from_str(DEFAULT_CONFIG_RON, Path::new("c.ron")).expect("default");
        c.inputs = ron::from_str(inputs).unwrap();
        c.outputs = ron::from_str(outputs).unwrap();
        c
    }

    #[test]
    fn a_config_with_nothing_is_touched_through_the_socket() {
        let s = TouchSources::of(&config("[]", "[]"));
        assert!(!s.has_device());
        assert_eq!(s.clients().len(), 1, "the socket is always a way in");
        assert_eq!(
            s.without_device().unwrap(),
            "no touch device configured: touches come only from clients: privileged clients of \
             the Unix socket (`touch` command: root, the daemon's user, socket.privileged)"
        );
    }

    #[test]
    fn the_viewer_and_tuio_are_named_and_a_read_only_viewer_is_said_to_be() {
        let s = TouchSources::of(&config(
            r#"[Tuio(listen: "0.0.0.0:3333")]"#,
            r#"[WebSocket(listen: "127.0.0.1:8080", privileged: true), WebSocket(listen: "127.0.0.1:8081")]"#,
        ));
        let line = s.without_device().unwrap();
        assert!(
            line.starts_with(
                "no touch device configured: touches come only from clients: TUIO senders to \
                 0.0.0.0:3333, the viewer page and the WebSocket clients of \
                 http://127.0.0.1:8080/ (`touch` command), privileged clients of the Unix socket"
            ),
            "{line}"
        );
        assert!(
            line.ends_with(
                "; the viewer of http://127.0.0.1:8081/ is read-only and cannot touch \
                 (privileged: true lets it)"
            ),
            "{line}"
        );
    }

    #[test]
    fn recordings_are_named_and_a_device_says_nothing() {
        let c = Config::from_str(DEFAULT_CONFIG_RON, Path::new("c.ron")).unwrap();
        let line = TouchSources::of(&c).without_device().unwrap();
        assert!(
            line.starts_with(
                "no touch device configured: touches come from the recordings of inputs[0] and \
                 from clients: privileged clients of the Unix socket"
            ),
            "{line}"
        );
        let s = TouchSources::of(&config("[Device(select: Auto)]", "[]"));
        assert!(s.has_device());
        assert_eq!(s.without_device(), None);
    }
}
