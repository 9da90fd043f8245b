#![no_main]
//! Bytes a WebSocket client sends, read by tungstenite in the server role (as the
//! WebSocket output configures it: a message size cap) from a memory stream; each
//! text message then goes through the protocol parser. Nothing panics; a message
//! over the cap is refused as a capacity error. Writes block (a client that reads
//! nothing), with the write buffer capped at one control frame as the output caps
//! it: pongs wait in place instead of piling up.
use crowdtouch::publish::protocol::parse_client_message;
use libfuzzer_sys::fuzz_target;
use std::io::{Cursor, Read, Write};
use tungstenite::protocol::{Role, WebSocketConfig};
use tungstenite::{Error, Message, WebSocket};

const MAX_MESSAGE_BYTES: usize = 4096;

/// Reads from the fuzz input; writes go nowhere.
struct Memory(Cursor<Vec<u8>>);

impl Read for Memory {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.0.read(buf)
    }
}

impl Write for Memory {
    fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
        Err(std::io::ErrorKind::WouldBlock.into())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

fuzz_target!(|data: &[u8]| {
    let config = WebSocketConfig::default()
        .write_buffer_size(0)
        .max_write_buffer_size(2 + 125)
        .max_message_size(Some(MAX_MESSAGE_BYTES))
        .max_frame_size(Some(MAX_MESSAGE_BYTES));
    let mut ws = WebSocket::from_raw_socket(
        Memory(Cursor::new(data.to_vec())),
        Role::Server,
        Some(config),
    );
    for _ in 0..256 {
        match ws.read() {
            Ok(Message::Text(t)) => {
                assert!(t.len() <= MAX_MESSAGE_BYTES);
                let _ = parse_client_message(t.as_bytes());
            }
            Ok(Message::Binary(b)) => assert!(b.len() <= MAX_MESSAGE_BYTES),
            Ok(_) => {}
            Err(Error::Capacity(_) | Error::Utf8(_) | Error::Protocol(_)) => break,
            Err(Error::Io(e)) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(_) => break,
        }
    }
});
