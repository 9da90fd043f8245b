//! What the text readers share: ids and frames as whole numbers, words shortened
//! for messages.

/// `v` as a whole number, if it is one in `0..2^53`.
pub(super) fn whole(v: f64) -> Option<u64> {
    (v.is_finite() && v >= 0.0 && v.fract() == 0.0 && v < 9.007_199_254_740_992e15)
        .then_some(v as u64)
}

/// A word of the input as a message shows it: its first 24 characters, control
/// characters escaped.
pub(super) fn clip(s: &str) -> String {
    let shown: String = s.chars().take(24).collect();
    crate::located::escape(&shown)
}
