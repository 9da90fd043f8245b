//! How people name a touch device in configs and on the command line.

/// Parses `"vvvv:pppp"` (hex, as `lsusb` prints it: `"2575:0204"`) into vendor and
/// product ids.
pub fn parse_vendor_product(s: &str) -> Option<(u16, u16)> {
    let (v, p) = s.trim().split_once(':')?;
    Some((
        u16::from_str_radix(v, 16).ok()?,
        u16::from_str_radix(p, 16).ok()?,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vendor_product_ids() {
        assert_eq!(parse_vendor_product("2575:0204"), Some((0x2575, 0x0204)));
        assert_eq!(parse_vendor_product("06CB:2968"), Some((0x06cb, 0x2968)));
        assert_eq!(parse_vendor_product("2575"), None);
        assert_eq!(parse_vendor_product("12345:1"), None);
    }
}
