//! The TUIO input's thread shell: a UDP socket read with a timeout, its buffer
//! reused, each datagram let through the [`FloodGate`] of its peer and handed to
//! the [`TuioDecoder`].

use super::decode::{log_rare, TuioCounters, TuioDecoder, TuioLimits};
use super::flood::{Admit, FloodGate};
use crate::input::{reader_timeout_ms, FrameSink};
use crate::rt::monotonic_now;
use crate::vocab::Micros;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Largest datagram read (the UDP maximum); longer ones are cut by the kernel and
/// then refused by the OSC reader.
pub const BUFFER_BYTES: usize = 65_536;

/// What the TUIO input is told by the config.
#[derive(Clone, Debug, PartialEq)]
pub struct TuioSettings {
    /// Where to listen.
    pub listen: SocketAddr,
    /// A sender silent this long has its touches lifted.
    pub timeout: Micros,
    /// Sessions per frame, senders, datagrams a second per peer.
    pub limits: TuioLimits,
}

/// Why the TUIO input could not start.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The UDP port could not be bound.
    #[error("TUIO input: cannot listen on {addr}: {source}")]
    Bind {
        /// The address.
        addr: SocketAddr,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
}

/// A bound TUIO input, run on its own input thread.
#[derive(Debug)]
pub struct TuioSource {
    socket: UdpSocket,
    decoder: Box<TuioDecoder>,
    gate: FloodGate,
    buf: Vec<u8>,
    counters: Arc<TuioCounters>,
}

impl TuioSource {
    /// Binds the UDP socket.
    ///
    /// # Errors
    /// [`Error::Bind`] naming the address (in use, not an address of this machine,
    /// a privileged port).
    pub fn bind(settings: &TuioSettings) -> Result<TuioSource, Error> {
        let bind_err = |source| Error::Bind {
            addr: settings.listen,
            source,
        };
        let socket = UdpSocket::bind(settings.listen).map_err(bind_err)?;
        let counters = Arc::new(TuioCounters::default());
        Ok(TuioSource {
            socket,
            decoder: Box::new(TuioDecoder::with_limits(
                settings.limits,
                settings.timeout,
                Arc::clone(&counters),
            )),
            gate: FloodGate::new(settings.limits.packets_per_s, settings.limits.senders),
            buf: vec![0; BUFFER_BYTES],
            counters,
        })
    }

    /// The address it listens on (the port chosen when the config said 0).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.socket.local_addr().ok()
    }

    /// Its counters.
    pub fn counters(&self) -> Arc<TuioCounters> {
        Arc::clone(&self.counters)
    }

    /// Reads datagrams into `sink` until `stop` is set (checked at least every
    /// [`STOP_CHECK_US`](crate::input::STOP_CHECK_US)); then ends every touch still
    /// down. Allocates nothing per datagram.
    pub fn run(&mut self, sink: &mut dyn FrameSink, stop: &AtomicBool) {
        let mut timeout_ms = 0;
        let rate = self.decoder.limits().packets_per_s;
        while !stop.load(Ordering::Relaxed) {
            let want = reader_timeout_ms(sink).max(1);
            if want != timeout_ms {
                timeout_ms = want;
                let d = Some(Duration::from_millis(u64::from(want)));
                if let Err(e) = self.socket.set_read_timeout(d) {
                    log::error!("TUIO input: cannot set the read timeout: {e}");
                    break;
                }
            }
            let got = self.socket.recv_from(&mut self.buf);
            let now = monotonic_now();
            match got {
                Ok((n, peer)) => match self.gate.admit(peer, now) {
                    Admit::Take => {
                        // Errors are counted and logged by the decoder.
                        let _ = self.decoder.packet(&self.buf[..n], peer, now, sink);
                    }
                    Admit::Drop => {
                        let c = self.counters.flood_dropped.fetch_add(1, Ordering::Relaxed) + 1;
                        log_rare(
                            c,
                            peer,
                            &format_args!(
                                "more than {rate} datagrams a second (max_packets_per_s): dropped"
                            ),
                        );
                    }
                },
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock
                            | std::io::ErrorKind::TimedOut
                            | std::io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => {
                    // ICMP errors and the like: nothing to do with the frames.
                    log::debug!("TUIO input: receive: {e}");
                }
            }
            self.decoder.expire(now, sink);
        }
        self.decoder.cancel_all(monotonic_now(), sink);
    }
}
