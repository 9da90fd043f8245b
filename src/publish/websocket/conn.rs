//! One WebSocket client as the WebSocket I/O thread serves it: first its HTTP
//! request head (answered with the page, an error status or the upgrade), then the
//! WebSocket stream, all on a non-blocking `TcpStream`.
//!
//! Once upgraded, the client is a client of the publisher like any Unix-socket
//! client: the same queue ([`ClientShared`]) with the same drop policy, and its text
//! messages go through the same [`Session`] (parser, command window, budget).
//! Every queued message is one WebSocket message: JSON as a text message (without
//! the newline), a binary snapshot as a binary message (the same bytes as on the
//! Unix socket, its frame header included). A `dropped` notice is a text message
//! of its own before the snapshot it is told with.
//!
//! # Who may connect (issue 27)
//! * `Host` must name the address the request reached (`127.0.0.1:PORT`,
//!   `[::1]:PORT`, and `localhost:PORT` on a loopback address) or one of the
//!   output's `hosts`; any other is refused **421 Misdirected Request** (RFC 9110
//!   §15.5.20: this server does not answer for that name), a missing one 400. A
//!   page that rebinds its own name to 127.0.0.1 (DNS rebinding) sends its own name.
//! * A WebSocket upgrade's `Origin` must be absent (not a browser: game engines,
//!   tools), the server's own origin (`http://` + the accepted `Host`: the viewer
//!   page it serves), or one of `origins` / `privileged_origins`; any other is
//!   refused **403 Forbidden**. Browsers send `Origin` on every upgrade and a page
//!   cannot forge it.
//! * Privilege: no `Origin` and the own origin get the output's `privileged`; an
//!   origin in `privileged_origins` is privileged; one only in `origins` is read-only.
//!
//! # Handshake and close codes (RFC 6455)
//! An upgrade must be HTTP/1.1 or later (§4.1 item 2), carry a `Sec-WebSocket-Key`
//! that is base64 of 16 bytes (§4.2.1 item 5), else 400; and version 13, else 426
//! with `Sec-WebSocket-Version: 13` (§4.2.2 item 4). Once open, a frame that breaks
//! the protocol (unmasked, RSV bits, unknown opcode, fragmented or oversize control
//! frame, a continuation out of place) closes with 1002, text or a close reason that
//! is not UTF-8 with 1007, a message over `max_message_bytes` with 1009 (§7.4.1):
//! the close frame goes out, then our side of the TCP connection is shut and
//! whatever else the client sends is discarded unread (§7.1.7, "Fail the WebSocket
//! Connection").
//!
//! # Pings and the write buffer
//! A ping is answered in place with one pong; while tungstenite's write buffer
//! holds anything, a newer ping's pong replaces the one waiting (its
//! `max_write_buffer_size` is [`MAX_CONTROL_FRAME_BYTES`] except while one of our
//! messages is being written), so a client that pings without reading holds at most
//! one of our messages and one pong in memory. Pings and pongs take from the same
//! budget as text messages ([`LINES_PER_SECOND`](crate::publish::socket::LINES_PER_SECOND)):
//! past it the client is not read until the budget refills.

use super::http::{self, HttpError, Request};
use super::options::WebSocketOptions;
use crate::publish::protocol::{self, Format};
use crate::publish::socket::{Acted, ClientShared, Hub, Item, PublisherStats, Session};
use crate::vocab::Micros;
use nix::sys::epoll::EpollFlags;
use std::io::{ErrorKind, Read, Write as _};
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::sync::Arc;
use std::time::Instant;
use tungstenite::error::ProtocolError;
use tungstenite::protocol::frame::coding::CloseCode;
use tungstenite::protocol::frame::CloseFrame;
use tungstenite::protocol::{Role, WebSocketConfig};
use tungstenite::{Error as WsError, Message, WebSocket};

/// Messages read from one client per round of the I/O loop.
const READ_MESSAGES_PER_ROUND: usize = 16;
/// Largest control frame a server writes (bytes): 2 header bytes and at most 125
/// of payload (RFC 6455 §5.5). tungstenite's write buffer is capped at this while
/// none of our messages is being written: one pong fits in an empty buffer, and
/// no pong piles up behind a message the client does not read.
pub(crate) const MAX_CONTROL_FRAME_BYTES: usize = 2 + 125;
/// Bytes discarded per round from a client whose connection has failed.
const DRAIN_BYTES_PER_ROUND: usize = 64 * 1024;

/// What the I/O thread should do with a connection after serving it.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Fate {
    /// Keep it.
    Keep,
    /// Remove it now.
    Remove,
}

/// What the request head asked for, once answered.
#[derive(Debug)]
pub(crate) enum Answer {
    /// Not complete yet.
    Wait,
    /// A response that ends the connection (page or error), and whether it is a
    /// refusal (counted, logged).
    Respond {
        bytes: Vec<u8>,
        refusal: Option<String>,
    },
    /// Upgrade: the 101 response, then the WebSocket stream.
    Upgrade { bytes: Vec<u8>, upgrade: Upgrade },
}

/// What an accepted upgrade carries to the WebSocket stream.
#[derive(Debug)]
pub(crate) struct Upgrade {
    /// Bytes the client sent after its head.
    pub rest: Vec<u8>,
    /// Whether the client is privileged (by its origin).
    pub privileged: bool,
}

/// `host` split into its lowercase name (an IPv6 address keeps its brackets) and
/// port (80 when absent, as browsers omit it); `None` when it is not `name[:port]`.
fn split_host(host: &str) -> Option<(String, u16)> {
    let host = host.to_ascii_lowercase();
    let (name, port) = if host.starts_with('[') {
        let end = host.find(']')?;
        match &host[end + 1..] {
            "" => (host[..=end].to_string(), None),
            p => (host[..=end].to_string(), Some(p.strip_prefix(':')?)),
        }
    } else {
        match host.rsplit_once(':') {
            Some((n, p)) => (n.to_string(), Some(p)),
            None => (host.clone(), None),
        }
    };
    let port = match port {
        Some(p) => p.parse().ok()?,
        None => 80,
    };
    (!name.is_empty()).then_some((name, port))
}

/// Whether a request's `Host` names this server: the address the connection
/// reached (`local`), `localhost` when that is a loopback address, or a configured
/// name (`name` on `local`'s port, `name:port` on that port).
pub(crate) fn host_accepted(host: &str, local: SocketAddr, hosts: &[String]) -> bool {
    let Some((name, port)) = split_host(host) else {
        return false;
    };
    if port != local.port() {
        return false;
    }
    let local_ip = local.ip().to_canonical();
    let bare = name.trim_start_matches('[').trim_end_matches(']');
    if bare
        .parse::<std::net::IpAddr>()
        .is_ok_and(|ip| ip.to_canonical() == local_ip)
    {
        return true;
    }
    if name == "localhost" && local_ip.is_loopback() {
        return true;
    }
    hosts.iter().any(|h| match h.rsplit_once(':') {
        Some((n, p)) if !h.ends_with(']') => n == name && p.parse() == Ok(port),
        _ => *h == name,
    })
}

/// Whether an upgrade from `origin` (its `Origin` header) may connect, and then
/// whether it is privileged; `Err` says why not. `host` is the accepted `Host`.
pub(crate) fn origin_privilege(
    origin: Option<&str>,
    host: &str,
    opts: &WebSocketOptions,
) -> Result<bool, String> {
    let Some(origin) = origin else {
        return Ok(opts.privileged);
    };
    let origin = origin.to_ascii_lowercase();
    if origin == format!("http://{}", host.to_ascii_lowercase()) {
        return Ok(opts.privileged);
    }
    if opts.privileged_origins.contains(&origin) {
        return Ok(true);
    }
    if opts.origins.contains(&origin) {
        return Ok(false);
    }
    Err(format!(
        "origin {:?} may not connect: only this server's own pages, and the output's \
         origins and privileged_origins",
        http::clip(&origin, 80)
    ))
}

/// Decides what to answer a complete request head that reached `local`, or
/// [`Answer::Wait`]; `metrics` makes the `/metrics` body when the output serves it.
pub(crate) fn answer(
    buf: &[u8],
    opts: &WebSocketOptions,
    page: &str,
    clients: usize,
    local: SocketAddr,
    metrics: &dyn Fn() -> String,
) -> Answer {
    let refuse = |status: u16, reason: &str, extra: &str, why: String| Answer::Respond {
        bytes: http::response(status, reason, extra, &format!("{why}\n")),
        refusal: Some(format!("{status} {reason}: {why}")),
    };
    let (req, len): (Request, usize) = match http::parse_request_head(buf) {
        Ok(Some(r)) => r,
        Ok(None) => return Answer::Wait,
        Err(e @ HttpError::TooLarge { .. }) => {
            return refuse(431, "Request Header Fields Too Large", "", e.to_string())
        }
        Err(e) => return refuse(400, "Bad Request", "", e.to_string()),
    };
    let Some(host) = req.host.clone() else {
        return refuse(
            400,
            "Bad Request",
            "",
            "a Host header is required".to_string(),
        );
    };
    if !host_accepted(&host, local, &opts.hosts) {
        return refuse(
            421,
            "Misdirected Request",
            "",
            format!(
                "this server does not answer for host {:?}: name {local} (or a name in the \
                 output's hosts)",
                http::clip(&host, 80)
            ),
        );
    }
    if req.method != "GET" {
        return refuse(
            405,
            "Method Not Allowed",
            "Allow: GET\r\n",
            format!("method {} is not allowed: only GET", req.method),
        );
    }
    if !req.upgrade {
        return match req.path.as_str() {
            "/" | "/index.html" if opts.viewer => Answer::Respond {
                bytes: http::page(page),
                refusal: None,
            },
            // The token, when the output has one, guards the figures too
            // (Prometheus: `authorization: {credentials: …}` in the scrape config).
            "/metrics" if opts.metrics => match &opts.token {
                Some(token)
                    if !req.token().is_some_and(|t| {
                        http::constant_time_eq(t.as_bytes(), token.as_bytes())
                    }) =>
                {
                    refuse(
                        401,
                        "Unauthorized",
                        "WWW-Authenticate: Bearer\r\n",
                        "/metrics needs the output's token: Authorization: Bearer or ?token="
                            .to_string(),
                    )
                }
                _ => Answer::Respond {
                    bytes: http::ok(crate::publish::metrics::CONTENT_TYPE, &metrics()),
                    refusal: None,
                },
            },
            "/ws" => refuse(
                426,
                "Upgrade Required",
                "Upgrade: websocket\r\n",
                "/ws is the WebSocket stream: connect with a WebSocket client".to_string(),
            ),
            p => refuse(404, "Not Found", "", format!("no such page: {p}")),
        };
    }
    if req.http_minor < 1 {
        return refuse(
            400,
            "Bad Request",
            "",
            "a WebSocket upgrade needs HTTP/1.1 or later (RFC 6455 §4.1)".to_string(),
        );
    }
    let privileged = match origin_privilege(req.origin.as_deref(), &host, opts) {
        Ok(p) => p,
        Err(why) => return refuse(403, "Forbidden", "", why),
    };
    if let Some(token) = &opts.token {
        let ok = req
            .token()
            .is_some_and(|t| http::constant_time_eq(t.as_bytes(), token.as_bytes()));
        if !ok {
            let why = if req.token().is_some() {
                "wrong token"
            } else {
                "a token is required: ?token= on the URL or Authorization: Bearer"
            };
            return refuse(
                401,
                "Unauthorized",
                "WWW-Authenticate: Bearer\r\n",
                why.to_string(),
            );
        }
    }
    let Some(key) = req.key.as_deref().filter(|k| !k.is_empty()) else {
        return refuse(
            400,
            "Bad Request",
            "",
            "a WebSocket upgrade needs Sec-WebSocket-Key".to_string(),
        );
    };
    if !http::valid_websocket_key(key) {
        return refuse(
            400,
            "Bad Request",
            "",
            "Sec-WebSocket-Key must be the base64 of 16 bytes (RFC 6455 §4.2.1)".to_string(),
        );
    }
    if req.version.as_deref() != Some("13") {
        return refuse(
            426,
            "Upgrade Required",
            "Sec-WebSocket-Version: 13\r\n",
            format!(
                "WebSocket version {:?} is not spoken: only 13",
                req.version.as_deref().unwrap_or("")
            ),
        );
    }
    if clients >= opts.max_clients as usize {
        return refuse(
            503,
            "Service Unavailable",
            "",
            format!("too many clients: {clients} connected (max_clients)"),
        );
    }
    Answer::Upgrade {
        bytes: http::switching_protocols(key),
        upgrade: Upgrade {
            rest: buf[len..].to_vec(),
            privileged,
        },
    }
}

/// Where a connection is in its life.
enum Phase {
    /// Reading the request head.
    Head { stream: TcpStream, buf: Vec<u8> },
    /// Writing a response; then the connection closes, or upgrades.
    Respond {
        stream: TcpStream,
        bytes: Vec<u8>,
        sent: usize,
        upgrade: Option<Upgrade>,
    },
    /// The WebSocket stream.
    Open(Box<Open>),
    /// Between two phases (never seen outside a method).
    Gone,
}

/// An upgraded client.
struct Open {
    ws: WebSocket<TcpStream>,
    session: Session,
    /// A text message read and not yet taken (window, budget or a held hello).
    pending: Option<Vec<u8>>,
    /// The last write left bytes in tungstenite's buffer: flush when writable.
    unflushed: bool,
    /// No more input is taken (the client closed, or was refused).
    input_done: bool,
    /// The close frame is queued: the connection ends once it is out.
    closed: bool,
    /// The close frame to send when the queue closes (the protocol error's code),
    /// instead of 1008 after an error message or 1001.
    close_frame: Option<CloseFrame>,
    /// The client broke the protocol: nothing more it sends is parsed; once our
    /// close frame is out our side is shut and its bytes are discarded.
    failed: bool,
}

impl Open {
    /// Runs `f` with tungstenite's write buffer uncapped (one of our messages, or a
    /// close frame, goes in whole), then caps it at [`MAX_CONTROL_FRAME_BYTES`] again.
    fn uncapped<T>(&mut self, f: impl FnOnce(&mut WebSocket<TcpStream>) -> T) -> T {
        self.ws.set_config(|c| c.max_write_buffer_size = usize::MAX);
        let out = f(&mut self.ws);
        self.ws
            .set_config(|c| c.max_write_buffer_size = MAX_CONTROL_FRAME_BYTES);
        out
    }

    /// Fails the connection with `code` (RFC 6455 §7.1.7): the client is told
    /// `message` as an error, then gets the close frame; nothing more is parsed.
    fn fail(&mut self, hub: &Hub, code: CloseCode, message: &str) {
        self.close_frame = Some(closing_frame(code, message));
        self.session.fatal(hub, message);
        self.input_done = true;
        self.failed = true;
    }
}

/// One connection, owned by the WebSocket I/O thread.
pub(crate) struct WsConn {
    phase: Phase,
    /// The peer, for log lines.
    pub peer: SocketAddr,
    /// The address the connection reached (what its `Host` must name).
    pub local: SocketAddr,
    /// When it connected (a request head must come within the handshake time).
    pub since: Instant,
    /// Lines wait (window, rate or a held hello): do not poll for input.
    pub paused: bool,
    /// The socket's buffer is full: wait until it is writable.
    pub blocked: bool,
    /// Since when the socket has taken no bytes while some were waiting.
    pub stalled_since: Option<Instant>,
    /// The events its socket is registered for.
    pub interest: EpollFlags,
}

/// The close code and reason a finished queue ends with.
fn closing_frame(code: CloseCode, reason: &str) -> CloseFrame {
    // A close reason is at most 123 bytes.
    let mut end = reason.len().min(123);
    while !reason.is_char_boundary(end) {
        end -= 1;
    }
    CloseFrame {
        code,
        reason: reason[..end].to_string().into(),
    }
}

impl WsConn {
    /// A new connection reading its request head.
    pub fn new(stream: TcpStream, peer: SocketAddr, local: SocketAddr) -> WsConn {
        WsConn {
            phase: Phase::Head {
                stream,
                buf: Vec::new(),
            },
            peer,
            local,
            since: Instant::now(),
            paused: false,
            blocked: false,
            stalled_since: None,
            interest: EpollFlags::empty(),
        }
    }

    /// The socket.
    pub fn stream(&self) -> Option<&TcpStream> {
        match &self.phase {
            Phase::Head { stream, .. } | Phase::Respond { stream, .. } => Some(stream),
            Phase::Open(o) => Some(o.ws.get_ref()),
            Phase::Gone => None,
        }
    }

    /// Whether it sent a `touch` command (its contacts are lifted when it leaves).
    pub fn touched(&self) -> bool {
        matches!(&self.phase, Phase::Open(o) if o.session.touched)
    }

    /// The publisher's side of this client, once upgraded.
    pub fn shared(&self) -> Option<&Arc<ClientShared>> {
        match &self.phase {
            Phase::Open(o) => Some(&o.session.shared),
            _ => None,
        }
    }

    /// Whether the upgrade is done.
    pub fn is_open(&self) -> bool {
        matches!(self.phase, Phase::Open(_))
    }

    /// Whether to poll the socket for input.
    pub fn wants_input(&self) -> bool {
        match &self.phase {
            Phase::Head { .. } => true,
            Phase::Respond { .. } | Phase::Gone => false,
            Phase::Open(o) => !self.paused && (!o.input_done || o.closed || o.failed),
        }
    }

    /// Reads the request head; once complete, answers it. `answer_head` decides.
    pub fn head_input(
        &mut self,
        decide: impl FnOnce(&[u8]) -> Answer,
        on_refusal: impl FnOnce(&str),
    ) -> Fate {
        let Phase::Head { stream, buf } = &mut self.phase else {
            return Fate::Keep;
        };
        let mut chunk = [0u8; 2048];
        loop {
            if buf.len() > http::MAX_REQUEST_HEAD_BYTES {
                break;
            }
            match stream.read(&mut chunk) {
                Ok(0) => return Fate::Remove,
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => return Fate::Remove,
            }
        }
        let (bytes, upgrade) = match decide(buf) {
            Answer::Wait => return Fate::Keep,
            Answer::Respond { bytes, refusal } => {
                if let Some(why) = refusal {
                    on_refusal(&why);
                }
                (bytes, None)
            }
            Answer::Upgrade { bytes, upgrade } => (bytes, Some(upgrade)),
        };
        let Phase::Head { stream, .. } = std::mem::replace(&mut self.phase, Phase::Gone) else {
            return Fate::Remove;
        };
        self.phase = Phase::Respond {
            stream,
            bytes,
            sent: 0,
            upgrade,
        };
        Fate::Keep
    }

    /// Whether the response is written and the connection should upgrade now
    /// (`Some`), or is done (`None` with [`Fate::Remove`]).
    pub fn respond(&mut self, now: Instant) -> (Fate, Option<Upgrade>) {
        let Phase::Respond {
            stream,
            bytes,
            sent,
            upgrade,
        } = &mut self.phase
        else {
            return (Fate::Keep, None);
        };
        while *sent < bytes.len() {
            match stream.write(&bytes[*sent..]) {
                Ok(0) => return (Fate::Remove, None),
                Ok(n) => {
                    *sent += n;
                    self.stalled_since = None;
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    self.blocked = true;
                    self.stalled_since.get_or_insert(now);
                    return (Fate::Keep, None);
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => return (Fate::Remove, None),
            }
        }
        self.blocked = false;
        match upgrade.take() {
            Some(u) => (Fate::Keep, Some(u)),
            None => {
                let _ = stream.shutdown(Shutdown::Write);
                (Fate::Remove, None)
            }
        }
    }

    /// Turns the written 101 response into the WebSocket stream of `shared`.
    pub fn upgrade(
        &mut self,
        shared: Arc<ClientShared>,
        rest: Vec<u8>,
        max_message_bytes: usize,
        now: Micros,
    ) {
        let Phase::Respond { stream, .. } = std::mem::replace(&mut self.phase, Phase::Gone) else {
            return;
        };
        let config = WebSocketConfig::default()
            .write_buffer_size(0)
            .max_write_buffer_size(MAX_CONTROL_FRAME_BYTES)
            .max_message_size(Some(max_message_bytes))
            .max_frame_size(Some(max_message_bytes));
        let ws = WebSocket::from_partially_read(stream, rest, Role::Server, Some(config));
        self.phase = Phase::Open(Box::new(Open {
            ws,
            session: Session::new(shared, now),
            pending: None,
            unflushed: false,
            input_done: false,
            closed: false,
            close_frame: None,
            failed: false,
        }));
    }

    /// Writes queued messages until the queue is empty or the socket is full.
    pub fn flush(&mut self, stats: &PublisherStats, now: Instant) -> Fate {
        let Phase::Open(o) = &mut self.phase else {
            return Fate::Keep;
        };
        loop {
            if o.unflushed || o.closed {
                match o.ws.flush() {
                    Ok(()) => o.unflushed = false,
                    Err(WsError::Io(e)) if e.kind() == ErrorKind::WouldBlock => {
                        self.blocked = true;
                        self.stalled_since.get_or_insert(now);
                        return Fate::Keep;
                    }
                    Err(WsError::ConnectionClosed) => return Fate::Remove,
                    Err(_) => return Fate::Remove,
                }
                self.stalled_since = None;
                if o.closed {
                    // Our close frame is out: wait for the client's (read), or
                    // until the close grace ends. A failed connection is not
                    // waited for: our side is shut (what it sends is discarded).
                    if o.failed {
                        let _ = o.ws.get_ref().shutdown(Shutdown::Write);
                    }
                    self.blocked = false;
                    return Fate::Keep;
                }
            }
            let mut q = o.session.shared.lock();
            if q.dead {
                return Fate::Remove;
            }
            let Some((item, unnotified, total)) = q.pop() else {
                self.blocked = false;
                self.stalled_since = None;
                if q.closing_since.is_some() {
                    drop(q);
                    let frame = if let Some(f) = o.close_frame.take() {
                        f
                    } else if o.input_done {
                        closing_frame(CloseCode::Policy, "protocol error: see the error message")
                    } else {
                        closing_frame(CloseCode::Away, "closing: see the last message")
                    };
                    o.closed = true;
                    o.input_done = true;
                    let _ = o.uncapped(|ws| ws.close(Some(frame)));
                    continue;
                }
                return Fate::Keep;
            };
            drop(q);
            let mut messages: [Option<Message>; 2] = [None, None];
            if unnotified > 0 {
                let mut notice = Vec::with_capacity(64);
                protocol::encode_dropped(unnotified, total, &mut notice);
                messages[0] = Some(text(notice));
            }
            let (message, len, snapshot) = ws_message(item, total);
            messages[1] = Some(message);
            for m in messages.into_iter().flatten() {
                match o.uncapped(|ws| ws.write(m)) {
                    Ok(()) => {}
                    Err(WsError::Io(e)) if e.kind() == ErrorKind::WouldBlock => {
                        // Kept in tungstenite's buffer; flushed when writable.
                        o.unflushed = true;
                    }
                    Err(_) => return Fate::Remove,
                }
            }
            stats.record_write(len, snapshot.is_some(), snapshot.flatten());
            if o.unflushed {
                self.blocked = true;
                self.stalled_since.get_or_insert(now);
                return Fate::Keep;
            }
        }
    }

    /// Reads what the client sent and acts on its messages, as far as its window,
    /// its budget and the read budget allow.
    pub fn input(&mut self, hub: &Hub, now: Micros) -> Fate {
        let peer = self.peer;
        let Phase::Open(o) = &mut self.phase else {
            return Fate::Keep;
        };
        self.paused = false;
        if o.failed {
            return drain(o.ws.get_mut());
        }
        for _ in 0..READ_MESSAGES_PER_ROUND {
            if !o.session.release_held(hub) {
                self.paused = true;
                return Fate::Keep;
            }
            if let Some(message) = o.pending.take() {
                if !o.session.may_take(now) {
                    o.pending = Some(message);
                    self.paused = true;
                    return Fate::Keep;
                }
                match o.session.act(hub, &message) {
                    Acted::Done => {}
                    Acted::Held => {
                        self.paused = true;
                        return Fate::Keep;
                    }
                    Acted::Fatal => o.input_done = true,
                }
            }
            match o.ws.read() {
                Ok(Message::Close(_)) => {
                    // tungstenite answers the close; what is queued no longer matters.
                    begin_close(o, None);
                    return Fate::Keep;
                }
                Ok(_) if o.input_done => {}
                Ok(Message::Text(t)) => o.pending = Some(t.as_bytes().to_vec()),
                Ok(Message::Binary(_)) => {
                    hub.stats.count_ws_bad_frame();
                    o.session.answer(
                        None,
                        "binary messages are not read: send protocol messages as JSON text",
                    );
                }
                Ok(_) => {
                    // A ping (its pong waits in tungstenite, one at most) or a
                    // pong: each takes from the message budget.
                    if !o.session.may_take(now) {
                        self.paused = true;
                        return Fate::Keep;
                    }
                }
                Err(WsError::Io(e)) if e.kind() == ErrorKind::WouldBlock => return Fate::Keep,
                Err(WsError::Io(e)) if e.kind() == ErrorKind::Interrupted => {}
                Err(WsError::Capacity(e)) => {
                    hub.stats.count_ws_oversize();
                    log::info!("WebSocket client {} ({peer}): {e}; closing", o.session.id());
                    let limit = o.ws.get_config().max_message_size.unwrap_or(0);
                    let reason = format!("message too big: the limit is {limit} bytes");
                    let frame = closing_frame(CloseCode::Size, &reason);
                    begin_close(o, None);
                    let _ = o.uncapped(|ws| ws.close(Some(frame)));
                    o.failed = true;
                    return Fate::Keep;
                }
                Err(WsError::Utf8(_)) => {
                    hub.stats.count_ws_bad_frame();
                    log::info!(
                        "WebSocket client {} ({peer}): text or a close reason is not UTF-8; closing",
                        o.session.id()
                    );
                    o.fail(
                        hub,
                        CloseCode::Invalid,
                        "a text message or close reason is not valid UTF-8 (RFC 6455 §8.1)",
                    );
                    return Fate::Keep;
                }
                Err(WsError::ConnectionClosed | WsError::AlreadyClosed) => return Fate::Remove,
                Err(WsError::Protocol(ProtocolError::ResetWithoutClosingHandshake)) => {
                    return Fate::Remove
                }
                Err(WsError::Protocol(e)) => {
                    hub.stats.count_ws_bad_frame();
                    log::info!(
                        "WebSocket client {} ({peer}): protocol violation: {e}; closing",
                        o.session.id()
                    );
                    let message = format!("WebSocket protocol error: {e} (RFC 6455 §5)");
                    o.fail(hub, CloseCode::Protocol, &message);
                    return Fate::Keep;
                }
                Err(e) => {
                    log::debug!("WebSocket client {} ({peer}): {e}", o.session.id());
                    return Fate::Remove;
                }
            }
        }
        Fate::Keep
    }

    /// Whether the close handshake is under way (the connection ends soon).
    pub fn closing(&self) -> bool {
        matches!(&self.phase, Phase::Open(o) if o.closed)
    }

    /// Ends the connection: our side shut.
    pub fn shut_down(&self) {
        if let Some(s) = self.stream() {
            let _ = s.shutdown(Shutdown::Both);
        }
    }
}

/// Discards what a failed connection's client still sends; [`Fate::Remove`] at its
/// end of stream (the close grace removes it otherwise).
fn drain(stream: &mut TcpStream) -> Fate {
    let mut sink = [0u8; 4096];
    let mut taken = 0;
    while taken < DRAIN_BYTES_PER_ROUND {
        match stream.read(&mut sink) {
            Ok(0) => return Fate::Remove,
            Ok(n) => taken += n,
            Err(e) if e.kind() == ErrorKind::WouldBlock => return Fate::Keep,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(_) => return Fate::Remove,
        }
    }
    Fate::Keep
}

/// Stops the client's stream and input, and starts the close handshake (with
/// `frame`, or as an answer to the client's close): the connection ends when the
/// client answers, or after the close grace.
fn begin_close(o: &mut Open, frame: Option<CloseFrame>) {
    {
        let mut q = o.session.shared.lock();
        q.dead = true;
        q.closing_since.get_or_insert_with(Instant::now);
    }
    o.input_done = true;
    o.closed = true;
    if frame.is_some() {
        let _ = o.ws.close(frame);
    }
}

/// A JSON message as a text message (newline removed).
fn text(mut json: Vec<u8>) -> Message {
    if json.last() == Some(&b'\n') {
        json.pop();
    }
    match String::from_utf8(json) {
        Ok(s) => Message::Text(s.into()),
        // Our encoders write UTF-8; should one not, the bytes still go out.
        Err(e) => Message::Binary(e.into_bytes().into()),
    }
}

/// A queued item as one WebSocket message, its length, and for a snapshot its
/// input time. `dropped_total` goes into a snapshot's `dropped`.
fn ws_message(item: Item, dropped_total: u64) -> (Message, usize, Option<Option<Micros>>) {
    match item {
        Item::Snapshot(enc) => {
            let at = enc.dropped_at.min(enc.bytes.len());
            let m = match enc.format {
                Format::Json => {
                    let mut digits = itoa::Buffer::new();
                    let d = digits.format(dropped_total).as_bytes();
                    let mut v = Vec::with_capacity(enc.bytes.len() + d.len());
                    v.extend_from_slice(&enc.bytes[..at]);
                    v.extend_from_slice(d);
                    v.extend_from_slice(&enc.bytes[at..]);
                    text(v)
                }
                Format::Binary => {
                    let mut v = enc.bytes.clone();
                    let at = protocol::BINARY_DROPPED_OFFSET;
                    if let Some(slot) = v.get_mut(at..at + 8) {
                        slot.copy_from_slice(&dropped_total.to_le_bytes());
                    }
                    Message::Binary(v.into())
                }
            };
            let len = m.len();
            (m, len, Some(enc.input_t))
        }
        Item::Mesh { json, .. } | Item::Poses { json, .. } | Item::Message { json, .. } => {
            let m = text(json.to_vec());
            let len = m.len();
            (m, len, None)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(privileged: bool) -> WebSocketOptions {
        WebSocketOptions {
            origins: vec!["https://kiosk.example".into()],
            privileged_origins: vec!["http://trusted.example:8081".into()],
            hosts: vec!["kiosk.local".into(), "proxy.local:9000".into()],
            ..WebSocketOptions::on("127.0.0.1:8080".parse().unwrap(), privileged, 4)
        }
    }

    fn local(s: &str) -> SocketAddr {
        s.parse().unwrap()
    }

    #[test]
    fn a_host_names_the_address_reached_localhost_or_a_configured_name() {
        let hosts = &opts(true).hosts;
        let v4 = local("127.0.0.1:8080");
        for ok in [
            "127.0.0.1:8080",
            "localhost:8080",
            "LocalHost:8080",
            "kiosk.local:8080",
        ] {
            assert!(host_accepted(ok, v4, hosts), "{ok}");
        }
        for bad in [
            "evil.example:8080",
            "127.0.0.1:8081",
            "127.0.0.1",
            "localhost",
            "kiosk.local:9000",
            "proxy.local:8080",
            "[::1]:8080",
            "127.0.0.1:80:80",
            ":8080",
            "",
        ] {
            assert!(!host_accepted(bad, v4, hosts), "{bad}");
        }
        // `name:port` entries name their own port (a proxy's).
        assert!(host_accepted(
            "proxy.local:9000",
            local("127.0.0.1:9000"),
            hosts
        ));
        let v6 = local("[::1]:8080");
        assert!(host_accepted("[::1]:8080", v6, hosts));
        assert!(host_accepted("[0:0:0:0:0:0:0:1]:8080", v6, hosts));
        assert!(host_accepted("localhost:8080", v6, hosts));
        assert!(!host_accepted("127.0.0.1:8080", v6, hosts));
        // A public address: itself, never localhost.
        let public = local("192.0.2.7:8080");
        assert!(host_accepted("192.0.2.7:8080", public, hosts));
        assert!(!host_accepted("localhost:8080", public, hosts));
        assert!(host_accepted("192.0.2.7", local("192.0.2.7:80"), hosts));
    }

    #[test]
    fn an_origin_is_own_listed_privileged_or_refused() {
        let host = "127.0.0.1:8080";
        for privileged in [true, false] {
            let o = opts(privileged);
            assert_eq!(origin_privilege(None, host, &o), Ok(privileged));
            assert_eq!(
                origin_privilege(Some("http://127.0.0.1:8080"), host, &o),
                Ok(privileged)
            );
            assert_eq!(
                origin_privilege(Some("HTTPS://Kiosk.Example"), host, &o),
                Ok(false)
            );
            assert_eq!(
                origin_privilege(Some("http://trusted.example:8081"), host, &o),
                Ok(true)
            );
        }
        let o = opts(true);
        for bad in [
            "http://evil.example",
            "https://127.0.0.1:8080",
            "http://localhost:8080",
            "null",
            "http://kiosk.example",
        ] {
            let e = origin_privilege(Some(bad), host, &o).unwrap_err();
            assert!(e.contains("may not connect"), "{bad}: {e}");
        }
        // The viewer opened as localhost: its own origin is that name.
        assert_eq!(
            origin_privilege(Some("http://localhost:8080"), "localhost:8080", &o),
            Ok(true)
        );
    }

    fn status(a: &Answer) -> u16 {
        match a {
            Answer::Upgrade { .. } => 101,
            Answer::Wait => 0,
            Answer::Respond { bytes, .. } => {
                String::from_utf8_lossy(&bytes[9..12]).parse().unwrap()
            }
        }
    }

    #[test]
    fn metrics_are_served_only_when_asked_for_and_with_the_token() {
        let at = local("127.0.0.1:8080");
        let body = || "crowdtouch_ticks_total 3\n".to_string();
        let get = |o: &WebSocketOptions, extra: &str| {
            answer(
                format!("GET /metrics HTTP/1.1\r\nHost: 127.0.0.1:8080\r\n{extra}\r\n").as_bytes(),
                o,
                "page",
                0,
                at,
                &body,
            )
        };
        let mut o = opts(true);
        assert_eq!(status(&get(&o, "")), 404, "off by default");
        o.metrics = true;
        let a = get(&o, "");
        assert_eq!(status(&a), 200);
        let Answer::Respond { bytes, .. } = a else {
            unreachable!()
        };
        let text = String::from_utf8(bytes).unwrap();
        assert!(text.contains("Content-Type: text/plain; version=0.0.4"));
        assert!(text.ends_with("\r\n\r\ncrowdtouch_ticks_total 3\n"));
        o.token = Some("0123456789abcdef".into());
        assert_eq!(status(&get(&o, "")), 401);
        assert_eq!(status(&get(&o, "Authorization: Bearer wrong\r\n")), 401);
        assert_eq!(
            status(&get(&o, "Authorization: Bearer 0123456789abcdef\r\n")),
            200
        );
    }

    #[test]
    fn answers_in_order_host_origin_version_key() {
        let o = opts(true);
        let at = local("127.0.0.1:8080");
        let none = String::new;
        let ask = |head: &str| status(&answer(head.as_bytes(), &o, "page", 0, at, &none));
        let up = |version: &str, host: &str, extra: &str, key: &str, v: &str| {
            format!(
                "GET /ws HTTP/{version}\r\nHost: {host}\r\nUpgrade: websocket\r\n\
                 Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n\
                 Sec-WebSocket-Version: {v}\r\n{extra}\r\n"
            )
        };
        let key = "dGhlIHNhbXBsZSBub25jZQ==";
        let h = "127.0.0.1:8080";
        assert_eq!(ask("GET / HTTP/1.1\r\n\r\n"), 400);
        assert_eq!(ask("GET / HTTP/1.1\r\nHost: evil:8080\r\n\r\n"), 421);
        assert_eq!(ask("GET / HTTP/1.1\r\nHost: 127.0.0.1:8080\r\n\r\n"), 200);
        assert_eq!(ask(&up("1.1", h, "", key, "13")), 101);
        assert_eq!(ask(&up("1.1", "evil:8080", "", key, "13")), 421);
        assert_eq!(ask(&up("1.0", h, "", key, "13")), 400);
        assert_eq!(
            ask(&up("1.1", h, "Origin: http://evil\r\n", key, "13")),
            403
        );
        assert_eq!(ask(&up("1.1", h, "", "abc", "13")), 400);
        assert_eq!(ask(&up("1.1", h, "", key, "8")), 426);
        let a = answer(
            up("1.1", h, "Origin: https://kiosk.example\r\n", key, "13").as_bytes(),
            &o,
            "page",
            0,
            at,
            &none,
        );
        assert!(matches!(
            a,
            Answer::Upgrade {
                upgrade: Upgrade {
                    privileged: false,
                    ..
                },
                ..
            }
        ));
    }
}
