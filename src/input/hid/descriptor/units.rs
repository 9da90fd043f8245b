//! Names of HID unit codes, decoded from the raw 32-bit value.

/// A readable name for a HID unit code (HID 1.11 §6.2.2.7), e.g. `"cm"`,
/// `"inch^3"`, `"cm*s^-1"`; `"none"` for 0.
pub fn unit_name(unit: u32) -> String {
    if unit == 0 {
        return "none".into();
    }
    let nibble = |i: u32| (unit >> (4 * i)) & 0xF;
    let exponent = |n: u32| if n >= 8 { n as i32 - 16 } else { n as i32 };
    let system = nibble(0);
    let (length, mass, temperature) = match system {
        1 => ("cm", "g", "K"),
        2 => ("rad", "g", "K"),
        3 => ("inch", "slug", "F"),
        4 => ("deg", "slug", "F"),
        0 => ("", "", ""),
        _ => return format!("vendor or reserved unit 0x{unit:x}"),
    };
    let mut parts = Vec::new();
    for (i, name) in [
        (1, length),
        (2, mass),
        (3, "s"),
        (4, temperature),
        (5, "A"),
        (6, "cd"),
    ] {
        let e = exponent(nibble(i));
        if e == 0 || name.is_empty() {
            continue;
        }
        parts.push(if e == 1 {
            name.to_string()
        } else {
            format!("{name}^{e}")
        });
    }
    if parts.is_empty() {
        format!("0x{unit:x}")
    } else {
        parts.join("*")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_names() {
        assert_eq!(unit_name(0x11), "cm");
        assert_eq!(unit_name(0x13), "inch");
        assert_eq!(unit_name(0x33), "inch^3");
        assert_eq!(unit_name(0), "none");
        assert_eq!(unit_name(0xF011), "cm*s^-1");
        assert!(unit_name(0x0F).contains("vendor"));
    }
}
