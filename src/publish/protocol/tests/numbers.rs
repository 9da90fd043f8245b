//! Fixed 3-decimal number writing.

use crate::publish::protocol::numbers::push_fixed3;

#[test]
fn fixed3_formats_exactly() {
    let cases = [
        (0.0, "0.000"),
        (-0.0004, "0.000"),
        (-0.0006, "-0.001"),
        (1.2345, "1.235"),
        (-12.3454, "-12.345"),
        (1e12, "1000000000.000"),
        (f64::NEG_INFINITY, "-1000000000.000"),
        (f64::NAN, "0.000"),
        (0.999_9, "1.000"),
        (5.05, "5.050"),
        (99.999_6, "100.000"),
        (123_456.789_1, "123456.789"),
        (-7.0, "-7.000"),
        (10.0, "10.000"),
    ];
    for (v, want) in cases {
        let mut out = Vec::new();
        push_fixed3(&mut out, v);
        assert_eq!(String::from_utf8(out).unwrap(), want, "{v}");
    }
}
