//! The TUIO input's thread shell: a UDP socket read with a timeout, its buffer
//! reused, datagrams handed to the [`TuioDecoder`].

use super::decode::{TuioCounters, TuioDecoder};
use crate::input::{reader_timeout_ms, FrameSink};
use crate::rt::monotonic_now;
use crate::vocab::Micros;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Largest datagram read (the UDP maximum); longer ones are cut by the kernel and
/// then refused by the OSC reader.
const BUFFER_BYTES: usize = 65_536;

/// Most datagrams taken in one second; further ones that second are dropped and
/// counted (a flood, not a tracker: reacTIVision sends one per camera frame).
pub const MAX_PACKETS_PER_S: u64 = 4_000;

/// What the TUIO input is told by the config.
#[derive(Clone, Debug, PartialEq)]
pub struct TuioSettings {
    /// Where to listen.
    pub listen: SocketAddr,
    /// A sender silent this long has its touches lifted.
    pub timeout: Micros,
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
            decoder: Box::new(TuioDecoder::new(settings.timeout, Arc::clone(&counters))),
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
        let mut second = monotonic_now();
        let mut in_second = 0u64;
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
                Ok((n, peer)) => {
                    if now.saturating_since(second).0 >= 1_000_000 {
                        second = now;
                        in_second = 0;
                    }
                    in_second += 1;
                    if in_second > MAX_PACKETS_PER_S {
                        let c = self.counters.flood_dropped.fetch_add(1, Ordering::Relaxed) + 1;
                        if c.is_power_of_two() {
                            log::warn!("tuio from {peer}: more than {MAX_PACKETS_PER_S} datagrams a second: dropped (seen {c} times)");
                        }
                    } else {
                        // Errors are counted and logged by the decoder.
                        let _ = self.decoder.packet(&self.buf[..n], peer, now, sink);
                    }
                }
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
