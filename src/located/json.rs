//! Words for JSON values in error messages.

use serde_json::Value;

/// What a JSON value is, for "expected a number, found a string" messages.
pub fn json_kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_has_its_article() {
        let v: Value = serde_json::from_str(r#"[null, true, 1, "s", [], {}]"#).unwrap();
        let kinds: Vec<_> = v.as_array().unwrap().iter().map(json_kind).collect();
        assert_eq!(
            kinds,
            [
                "null",
                "a boolean",
                "a number",
                "a string",
                "an array",
                "an object"
            ]
        );
    }
}
