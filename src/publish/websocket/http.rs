//! The HTTP request head a browser sends before the WebSocket upgrade (or to get
//! the viewer page), parsed with `httparse` under a hard size cap, and the few
//! responses the server gives.
//!
//! Only what the server acts on is kept: the method, the path and its `token`
//! query parameter, the HTTP version, `Host` and `Origin`, the `Authorization:
//! Bearer` token, and the upgrade headers. A second `Host` or `Origin` line makes
//! the head malformed (RFC 9112 §3.2: a request with more than one `Host` is
//! answered 400).

use thiserror::Error;

/// Largest request head accepted (bytes); a longer one is answered 431.
pub const MAX_REQUEST_HEAD_BYTES: usize = 8 * 1024;
/// Most header lines accepted; more is answered 431.
const MAX_HEADERS: usize = 32;

/// Why a request head is refused.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum HttpError {
    /// The head passed [`MAX_REQUEST_HEAD_BYTES`] or had too many header lines.
    #[error("request head too large: more than {max} bytes or {MAX_HEADERS} header lines")]
    TooLarge {
        /// The cap.
        max: usize,
    },
    /// Not an HTTP/1.x request head.
    #[error("malformed HTTP request at byte {at}: {reason}")]
    Malformed {
        /// Bytes of the head read when it went wrong (the head's length at most).
        at: usize,
        /// httparse's reason, or ours.
        reason: String,
    },
}

/// A parsed request head: what the server routes on.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Request {
    /// `GET`, `POST`, ...
    pub method: String,
    /// The path without its query (`/`, `/ws`).
    pub path: String,
    /// The `token` query parameter, percent-decoded.
    pub query_token: Option<String>,
    /// The token of an `Authorization: Bearer <token>` header.
    pub bearer: Option<String>,
    /// `Upgrade: websocket` was asked for (with `Connection: upgrade`).
    pub upgrade: bool,
    /// `Sec-WebSocket-Key`.
    pub key: Option<String>,
    /// `Sec-WebSocket-Version`.
    pub version: Option<String>,
    /// The HTTP minor version: 0 for HTTP/1.0, 1 for HTTP/1.1.
    pub http_minor: u8,
    /// The `Host` header, trimmed.
    pub host: Option<String>,
    /// The `Origin` header, trimmed (browsers send it with every WebSocket upgrade).
    pub origin: Option<String>,
}

impl Request {
    /// The token the client presented: the `?token=` parameter, else the bearer token.
    pub fn token(&self) -> Option<&str> {
        self.query_token.as_deref().or(self.bearer.as_deref())
    }
}

/// Parses the request head at the start of `buf`: `Ok(None)` while it is
/// incomplete (read more), `Ok(Some((request, head_len)))` once complete; the
/// bytes after `head_len` belong to the WebSocket stream.
///
/// # Errors
/// [`HttpError::TooLarge`] when the head passes [`MAX_REQUEST_HEAD_BYTES`] (or
/// `buf` holds more than that without a complete head), [`HttpError::Malformed`]
/// for anything that is not an HTTP/1.x request head.
pub fn parse_request_head(buf: &[u8]) -> Result<Option<(Request, usize)>, HttpError> {
    let window = &buf[..buf.len().min(MAX_REQUEST_HEAD_BYTES)];
    let mut headers = [httparse::EMPTY_HEADER; MAX_HEADERS];
    let mut req = httparse::Request::new(&mut headers);
    let len = match req.parse(window) {
        Ok(httparse::Status::Complete(len)) => len,
        Ok(httparse::Status::Partial) if buf.len() >= MAX_REQUEST_HEAD_BYTES => {
            return Err(HttpError::TooLarge {
                max: MAX_REQUEST_HEAD_BYTES,
            })
        }
        Ok(httparse::Status::Partial) => return Ok(None),
        Err(httparse::Error::TooManyHeaders) => {
            return Err(HttpError::TooLarge {
                max: MAX_REQUEST_HEAD_BYTES,
            })
        }
        Err(e) => {
            return Err(HttpError::Malformed {
                at: window.len(),
                reason: e.to_string(),
            })
        }
    };
    let method = req.method.unwrap_or_default().to_string();
    let target = req.path.unwrap_or_default();
    if !target.starts_with('/') {
        return Err(HttpError::Malformed {
            at: len,
            reason: format!("request target {target:?} is not a path"),
        });
    }
    let (path, query) = target.split_once('?').unwrap_or((target, ""));
    let mut out = Request {
        http_minor: req.version.unwrap_or(1),
        method,
        path: path.to_string(),
        query_token: query_param(query, "token"),
        ..Request::default()
    };
    let (mut upgrade_ws, mut connection_upgrade) = (false, false);
    for h in req.headers.iter() {
        let value = String::from_utf8_lossy(h.value);
        let value = value.trim();
        if h.name.eq_ignore_ascii_case("upgrade") {
            upgrade_ws |= value
                .split(',')
                .any(|v| v.trim().eq_ignore_ascii_case("websocket"));
        } else if h.name.eq_ignore_ascii_case("connection") {
            connection_upgrade |= value
                .split(',')
                .any(|v| v.trim().eq_ignore_ascii_case("upgrade"));
        } else if h.name.eq_ignore_ascii_case("sec-websocket-key") {
            out.key = Some(value.to_string());
        } else if h.name.eq_ignore_ascii_case("sec-websocket-version") {
            out.version = Some(value.to_string());
        } else if h.name.eq_ignore_ascii_case("host") || h.name.eq_ignore_ascii_case("origin") {
            let slot = if h.name.eq_ignore_ascii_case("host") {
                &mut out.host
            } else {
                &mut out.origin
            };
            if slot.is_some() {
                return Err(HttpError::Malformed {
                    at: len,
                    reason: format!("more than one {} header", h.name),
                });
            }
            *slot = Some(value.to_string());
        } else if h.name.eq_ignore_ascii_case("authorization") {
            if let Some((scheme, token)) = value.split_once(' ') {
                if scheme.eq_ignore_ascii_case("bearer") {
                    out.bearer = Some(token.trim().to_string());
                }
            }
        }
    }
    out.upgrade = upgrade_ws && connection_upgrade;
    Ok(Some((out, len)))
}

/// Whether `key` is a `Sec-WebSocket-Key` as RFC 6455 §4.2.1 item 5 wants it: the
/// base64 encoding (RFC 4648 §4, padded, canonical) of exactly 16 bytes, that is
/// 22 alphabet characters then `==`, the last one carrying no stray bits.
pub fn valid_websocket_key(key: &str) -> bool {
    let b = key.as_bytes();
    let value = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' => Some(62),
        b'/' => Some(63),
        _ => None,
    };
    // 16 bytes = 5 groups of 3 (20 characters) + 1 byte (2 characters + "==");
    // that last byte's 8 bits fill 6 + 2 bits, so the 22nd character's low 4 bits are 0.
    b.len() == 24
        && &b[22..] == b"=="
        && b[..22].iter().all(|&c| value(c).is_some())
        && value(b[21]).is_some_and(|v| v & 0x0f == 0)
}

/// The percent-decoded value of `name` in a query string.
fn query_param(query: &str, name: &str) -> Option<String> {
    query.split('&').find_map(|kv| {
        let (k, v) = kv.split_once('=').unwrap_or((kv, ""));
        (k == name).then(|| percent_decode(v))
    })
}

/// `%XX` escapes and `+` decoded; an invalid escape stays as it is.
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'%' if i + 2 < b.len() => {
                let hex = std::str::from_utf8(&b[i + 1..i + 3])
                    .ok()
                    .and_then(|h| u8::from_str_radix(h, 16).ok());
                match hex {
                    Some(v) => {
                        out.push(v);
                        i += 3;
                    }
                    None => {
                        out.push(b'%');
                        i += 1;
                    }
                }
            }
            b'+' => {
                out.push(b' ');
                i += 1;
            }
            c => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// At most the first `max` bytes of `s` (cut at a character boundary), for quoting
/// a client's header in a response or a log line; quote it with `{:?}`, which
/// escapes control characters.
pub fn clip(s: &str, max: usize) -> &str {
    let mut end = s.len().min(max);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    &s[..end]
}

/// Whether `a` and `b` are equal, in a time that depends on their lengths only
/// (a token compared this way leaks nothing of how much of it was right).
pub fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    let n = a.len().max(b.len());
    let mut diff = u8::from(a.len() != b.len());
    for i in 0..n {
        let x = a.get(i).copied().unwrap_or(0);
        let y = b.get(i).copied().unwrap_or(0);
        diff |= x ^ y;
    }
    std::hint::black_box(diff) == 0
}

/// A complete response that closes the connection: status line, headers, body.
pub fn response(status: u16, reason: &str, extra_headers: &str, body: &str) -> Vec<u8> {
    format!(
        "HTTP/1.1 {status} {reason}\r\nContent-Type: text/plain; charset=utf-8\r\n\
         Content-Length: {}\r\nConnection: close\r\nCache-Control: no-store\r\n{extra_headers}\r\n{body}",
        body.len()
    )
    .into_bytes()
}

/// The viewer page.
pub fn page(html: &str) -> Vec<u8> {
    ok("text/html; charset=utf-8", html)
}

/// A `200 OK` with `body` of `content_type`, not to be cached.
pub fn ok(content_type: &str, body: &str) -> Vec<u8> {
    format!(
        "HTTP/1.1 200 OK\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\
         Connection: close\r\nCache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\n\r\n{body}",
        body.len()
    )
    .into_bytes()
}

/// The `101 Switching Protocols` answer to an upgrade with key `key`.
pub fn switching_protocols(key: &str) -> Vec<u8> {
    let accept = tungstenite::handshake::derive_accept_key(key.as_bytes());
    format!(
        "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Accept: {accept}\r\n\r\n"
    )
    .into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    const UPGRADE: &[u8] = b"GET /ws?x=1&token=abc%2Bd+e HTTP/1.1\r\nHost: h\r\n\
        Upgrade: websocket\r\nConnection: keep-alive, Upgrade\r\n\
        Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\nrest";

    #[test]
    fn an_upgrade_is_read_with_its_token_and_key() {
        let (r, len) = parse_request_head(UPGRADE).unwrap().unwrap();
        assert_eq!(&UPGRADE[len..], b"rest");
        assert_eq!(r.method, "GET");
        assert_eq!(r.path, "/ws");
        assert_eq!(r.token(), Some("abc+d e"));
        assert!(r.upgrade);
        assert_eq!(r.key.as_deref(), Some("dGhlIHNhbXBsZSBub25jZQ=="));
        assert_eq!(r.version.as_deref(), Some("13"));
        // RFC 6455's example key and accept value.
        let resp = String::from_utf8(switching_protocols(r.key.as_deref().unwrap())).unwrap();
        assert!(resp.contains("Sec-WebSocket-Accept: s3pPLMBiTxaQ9kYGzzhZRbK+xOo=\r\n"));
    }

    #[test]
    fn a_bearer_token_and_a_plain_get() {
        let head = b"GET / HTTP/1.1\r\nAuthorization: Bearer s3cret\r\n\r\n";
        let (r, _) = parse_request_head(head).unwrap().unwrap();
        assert_eq!(
            (r.path.as_str(), r.token(), r.upgrade),
            ("/", Some("s3cret"), false)
        );
    }

    #[test]
    fn partial_oversize_and_garbage_heads() {
        assert_eq!(
            parse_request_head(b"GET / HTTP/1.1\r\nHost: h\r\n"),
            Ok(None)
        );
        let mut big = b"GET / HTTP/1.1\r\nX: ".to_vec();
        big.resize(MAX_REQUEST_HEAD_BYTES + 10, b'a');
        assert_eq!(
            parse_request_head(&big),
            Err(HttpError::TooLarge {
                max: MAX_REQUEST_HEAD_BYTES
            })
        );
        let mut many = b"GET / HTTP/1.1\r\n".to_vec();
        for i in 0..40 {
            many.extend_from_slice(format!("X{i}: y\r\n").as_bytes());
        }
        many.extend_from_slice(b"\r\n");
        assert!(matches!(
            parse_request_head(&many),
            Err(HttpError::TooLarge { .. })
        ));
        let e = parse_request_head(b"\x16\x03\x01 hello\r\n\r\n").unwrap_err();
        assert!(e.to_string().starts_with("malformed HTTP request"), "{e}");
        let e = parse_request_head(b"GET http://x/ HTTP/1.1\r\n\r\n").unwrap_err();
        assert!(e.to_string().contains("not a path"), "{e}");
    }

    #[test]
    fn the_version_host_and_origin_are_read_and_kept_single() {
        let head =
            b"GET /ws HTTP/1.0\r\nHost: 127.0.0.1:8080\r\nOrigin: http://evil.example\r\n\r\n";
        let (r, _) = parse_request_head(head).unwrap().unwrap();
        assert_eq!(r.http_minor, 0);
        assert_eq!(r.host.as_deref(), Some("127.0.0.1:8080"));
        assert_eq!(r.origin.as_deref(), Some("http://evil.example"));
        let (r, _) = parse_request_head(UPGRADE).unwrap().unwrap();
        assert_eq!((r.http_minor, r.origin), (1, None));
        let two = b"GET / HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n";
        let e = parse_request_head(two).unwrap_err();
        assert!(e.to_string().contains("more than one Host"), "{e}");
        let two = b"GET / HTTP/1.1\r\nHost: a\r\nOrigin: http://a\r\norigin: http://b\r\n\r\n";
        assert!(parse_request_head(two).is_err());
    }

    #[test]
    fn a_websocket_key_is_16_bytes_of_base64() {
        assert!(valid_websocket_key("dGhlIHNhbXBsZSBub25jZQ=="));
        assert!(valid_websocket_key("AAAAAAAAAAAAAAAAAAAAAA=="));
        assert!(valid_websocket_key("/+/+/+/+/+/+/+/+/+/+/w=="));
        for bad in [
            "",
            "not base64 at all!!!!!!=",
            "dGhlIHNhbXBsZSBub25jZQ",     // no padding
            "dGhlIHNhbXBsZSBub25jZR==",   // stray bits in the last character
            "dGhlIHNhbXBsZSBub25jZQ==AA", // 17+ bytes
            "dGhlIHNhbXBsZSBub25j",       // 15 bytes
            "dGhlIHNhbXBsZSBub25jZQ=A",
            "dGhlIHNhbXBsZS Bub25jZQ=",
        ] {
            assert!(!valid_websocket_key(bad), "{bad:?}");
        }
    }

    #[test]
    fn tokens_compare_whole() {
        assert!(constant_time_eq(b"0123456789abcdef", b"0123456789abcdef"));
        assert!(!constant_time_eq(b"0123456789abcdef", b"0123456789abcdeF"));
        assert!(!constant_time_eq(b"0123456789abcdef", b"0123456789abcde"));
        assert!(!constant_time_eq(b"", b"x"));
        assert!(constant_time_eq(b"", b""));
    }

    #[test]
    fn percent_escapes() {
        assert_eq!(percent_decode("a%20b%zz%4"), "a b%zz%4");
    }
}
