#![no_main]
//! The WebSocket output's HTTP request-head parser: any bytes give a request, "read
//! more", or an error that says what and where; never a panic, never a head longer
//! than the cap.
use crowdtouch::publish::websocket::{
    parse_request_head, valid_websocket_key, HttpError, MAX_REQUEST_HEAD_BYTES,
};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match parse_request_head(data) {
        Ok(Some((req, len))) => {
            assert!(len <= data.len() && len <= MAX_REQUEST_HEAD_BYTES);
            assert!(req.path.starts_with('/'));
            let _ = req.token();
            assert!(req.http_minor <= 1);
            // A key passes only as 24 characters ending "==" (16 bytes of base64).
            if let Some(key) = &req.key {
                if valid_websocket_key(key) {
                    assert!(key.len() == 24 && key.ends_with("=="));
                }
            }
        }
        Ok(None) => assert!(data.len() < MAX_REQUEST_HEAD_BYTES),
        Err(e @ HttpError::Malformed { .. }) => assert!(!e.to_string().is_empty()),
        Err(HttpError::TooLarge { max }) => assert_eq!(max, MAX_REQUEST_HEAD_BYTES),
    }
    // Every prefix of a head is "read more" or the same answer's error, never a panic.
    for cut in [1, data.len() / 2] {
        let _ = parse_request_head(&data[..cut.min(data.len())]);
    }
});
