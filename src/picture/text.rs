//! Text and numbers as they are written into a document.

/// XML text escaping, safe in element text and in attribute values.
pub fn escape(t: &str) -> String {
    let mut out = String::with_capacity(t.len());
    for c in t.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            c => out.push(c),
        }
    }
    out
}

/// A page coordinate or length in pixels: one decimal, without a trailing `.0`
/// and without a negative zero.
pub fn px(x: f64) -> String {
    let s = format!("{x:.1}");
    match s.strip_suffix(".0") {
        Some("-0") => "0".into(),
        Some(t) => t.into(),
        None if s == "-0.0" => "0".into(),
        None => s,
    }
}

/// A quantity for a reader (metres, seconds): at most three decimals, trailing
/// zeros dropped, no negative zero.
pub fn num(x: f64) -> String {
    let s = format!("{x:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// `x,y` in pixels, as in `points` lists.
pub fn pair(p: (f64, f64)) -> String {
    format!("{},{}", px(p.0), px(p.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escaping_covers_text_and_attributes() {
        assert_eq!(escape(r#"a<b & "c">"#), "a&lt;b &amp; &quot;c&quot;&gt;");
        assert_eq!(escape("σ_min_dis → ok"), "σ_min_dis → ok");
    }

    #[test]
    fn pixels_keep_one_decimal_and_drop_zeros() {
        assert_eq!(px(12.0), "12");
        assert_eq!(px(12.04), "12");
        assert_eq!(px(12.06), "12.1");
        assert_eq!(px(-0.04), "0");
        assert_eq!(px(-3.25), "-3.2");
        assert_eq!(pair((1.0, 2.5)), "1,2.5");
    }

    #[test]
    fn quantities_keep_three_decimals_at_most() {
        assert_eq!(num(0.5), "0.5");
        assert_eq!(num(2.0), "2");
        assert_eq!(num(1.23456), "1.235");
        assert_eq!(num(-0.0001), "0");
    }
}
