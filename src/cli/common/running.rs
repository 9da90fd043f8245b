//! A started daemon that is stopped however the command that started it ends.

use crowdtouch::pipeline::Daemon;

/// A started daemon, shut down however the command ends: at the end of
/// [`supervise`], on an early return (`?`), or by a panic unwinding through it. Its
/// socket file goes with it.
pub struct Running(pub Option<Daemon>);

impl Running {
    /// Stops every thread (`Daemon::shutdown`); the socket file goes with them.
    pub fn shutdown(mut self) {
        if let Some(d) = self.0.take() {
            d.shutdown();
        }
    }
}

impl std::ops::Deref for Running {
    type Target = Daemon;
    fn deref(&self) -> &Daemon {
        // `None` only inside `shutdown` and `drop`, which consume it.
        self.0.as_ref().expect("daemon already shut down")
    }
}

impl std::ops::DerefMut for Running {
    fn deref_mut(&mut self) -> &mut Daemon {
        self.0.as_mut().expect("daemon already shut down")
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if let Some(d) = self.0.take() {
            log::info!("stopping");
            d.shutdown();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crowdtouch::config::Config;
    use crowdtouch::pipeline::{DaemonOptions, SourceSpec};

    #[test]
    fn a_panic_unwinding_through_a_running_daemon_stops_it_and_removes_its_socket() {
        let dir = tempfile::tempdir().unwrap();
        let socket_path = dir.path().join("s.sock");
        let (_tx, rx) = crossbeam_channel::bounded(1);
        let mut cfg = Config::embedded_default();
        cfg.crowd.agents = 20;
        cfg.pipeline.realtime = Default::default();
        let daemon = Daemon::start(
            cfg,
            vec![SourceSpec::Channel { rx, glass_mm: None }],
            DaemonOptions {
                socket_path: socket_path.clone(),
                collect: None,
            },
        )
        .unwrap();
        let running = Running(Some(daemon));
        assert!(socket_path.exists());
        let unwound = std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || {
            let _running = running;
            panic!("a bug in the supervisor");
        }));
        assert!(unwound.is_err());
        assert!(!socket_path.exists(), "the socket outlived the panic");
    }
}
