//! Editing config text in place: comments and layout are kept.

use super::error::EditError;
use super::inputs::InputConfig;
use super::model::Config;
use crate::located::field_positions;
use std::path::Path;

/// Writes a calibration matrix into the config text of input `input` (a `Device`
/// input), keeping every comment and the rest of the text as it is: replaces the
/// value of `inputs[N].calibration.matrix`, or adds the field. The result is
/// validated before it is returned.
///
/// # Errors
/// [`EditError`]: the text is not a valid config, input `input` is not a `Device`
/// input, the text cannot be edited safely, or the result is not a valid config.
pub fn set_calibration_matrix(text: &str, input: usize, m: [f64; 6]) -> Result<String, EditError> {
    let value = format!(
        "Some(({}, {}, {}, {}, {}, {}))",
        fmt6(m[0]),
        fmt6(m[1]),
        fmt6(m[2]),
        fmt6(m[3]),
        fmt6(m[4]),
        fmt6(m[5])
    );
    let cfg = Config::from_str(text, Path::new("<config>")).map_err(EditError::InvalidText)?;
    if !matches!(cfg.inputs.get(input), Some(InputConfig::Device { .. })) {
        return Err(EditError::NotDevice { input });
    }
    let fields = field_positions(text);
    let offset = |line: usize, col: usize| -> Option<usize> {
        let mut off = 0;
        for (i, l) in text.split_inclusive('\n').enumerate() {
            if i + 1 == line {
                return l.char_indices().nth(col - 1).map(|(b, _)| off + b);
            }
            off += l.len();
        }
        None
    };
    let find = |path: &str| {
        fields
            .iter()
            .find(|(p, _, _)| p == path)
            .and_then(|(_, l, c)| offset(*l, *c))
    };
    let edited = if let Some(at) = find(&format!("inputs[{input}].calibration.matrix")) {
        // Replace the value after `matrix:` up to the end of `None` or the `Some(...)`.
        let colon = at
            + text[at..]
                .find(':')
                .ok_or(cannot_edit("no ':' after matrix"))?
            + 1;
        let start = colon + (text[colon..].len() - text[colon..].trim_start().len());
        let rest = &text[start..];
        let end = if rest.starts_with("None") {
            start + 4
        } else if rest.starts_with("Some") {
            let open = start + rest.find('(').ok_or(cannot_edit("no '(' after Some"))?;
            let mut depth = 0usize;
            let mut end = None;
            for (i, ch) in text[open..].char_indices() {
                match ch {
                    '(' | '[' => depth += 1,
                    ')' | ']' => {
                        depth -= 1;
                        if depth == 0 {
                            end = Some(open + i + 1);
                            break;
                        }
                    }
                    _ => {}
                }
            }
            end.ok_or(cannot_edit("unbalanced parentheses in matrix"))?
        } else {
            return Err(cannot_edit(
                "the matrix value is neither None nor Some(...)",
            ));
        };
        format!("{}{}{}", &text[..start], value, &text[end..])
    } else if let Some(at) = find(&format!("inputs[{input}].calibration")) {
        let open = at
            + text[at..]
                .find('(')
                .ok_or(cannot_edit("no '(' after calibration"))?
            + 1;
        format!("{}matrix: {}, {}", &text[..open], value, &text[open..])
    } else {
        // Neither: add `calibration: (...)` right after `Device(` of that input.
        let inputs_at = find("inputs").ok_or(cannot_edit("no inputs field"))?;
        let mut idx = 0;
        let mut search = inputs_at;
        let mut pos = None;
        while let Some(rel) = text[search..].find("Device(") {
            let p = search + rel;
            if idx == input {
                pos = Some(p + "Device(".len());
                break;
            }
            idx += 1;
            search = p + 1;
        }
        let p = pos.ok_or(cannot_edit("cannot find the Device input in the text"))?;
        format!(
            "{}calibration: (matrix: {}), {}",
            &text[..p],
            value,
            &text[p..]
        )
    };
    Config::from_str(&edited, Path::new("<edited>")).map_err(EditError::InvalidResult)?;
    Ok(edited)
}

fn cannot_edit(reason: &'static str) -> EditError {
    EditError::CannotEdit { reason }
}

fn fmt6(v: f64) -> String {
    let s = format!("{v:.6}");
    if s == "-0.000000" {
        "0.000000".into()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::load::DEFAULT_CONFIG_RON;

    const KIOSK: &str = include_str!("../../config/kiosk.ron");
    const KIOSK_CALIBRATION: &str =
        "            calibration: (rotation: 0, flip_x: false, flip_y: false, matrix: None),\n";
    const M: [f64; 6] = [0.0, -1.0, 1.0, 1.0, 0.0, 0.0];

    #[test]
    fn calibration_matrix_is_written_in_place_keeping_comments() {
        let out = set_calibration_matrix(KIOSK, 0, M).unwrap();
        let c = Config::from_str(&out, Path::new("k")).unwrap();
        match &c.inputs[0] {
            InputConfig::Device { calibration, .. } => assert_eq!(calibration.matrix, Some(M)),
            _ => panic!("not a device"),
        }
        // Only the value changed: every comment line is still there.
        let comments = |t: &str| {
            t.lines()
                .filter(|l| l.trim_start().starts_with("//"))
                .count()
        };
        assert_eq!(comments(&out), comments(KIOSK));
        // Writing again replaces the Some(...) value.
        let again = set_calibration_matrix(&out, 0, [1.0, 0.0, 0.0, 0.0, 1.0, 0.0]).unwrap();
        assert!(again.contains(
            "matrix: Some((1.000000, 0.000000, 0.000000, 0.000000, 1.000000, 0.000000))"
        ));
        // An input without a calibration field gets one.
        let bare = KIOSK.replace(KIOSK_CALIBRATION, "");
        let added = set_calibration_matrix(&bare, 0, M).unwrap();
        assert!(Config::from_str(&added, Path::new("k")).is_ok());
    }

    #[test]
    fn text_that_is_not_a_config_is_refused_with_the_configs_own_message() {
        let text = "(version: 1,, )";
        let e = set_calibration_matrix(text, 0, M).unwrap_err();
        assert!(matches!(e, EditError::InvalidText(_)), "{e:?}");
        let own = Config::from_str(text, Path::new("<config>"))
            .unwrap_err()
            .to_string();
        assert!(own.starts_with("<config>:1:"), "{own}");
        assert_eq!(e.to_string(), own);
    }

    #[test]
    fn an_input_that_is_not_a_device_is_refused() {
        // Replay inputs cannot be calibrated; nor can an input that is not there.
        let e = set_calibration_matrix(DEFAULT_CONFIG_RON, 0, M).unwrap_err();
        assert!(matches!(e, EditError::NotDevice { input: 0 }), "{e:?}");
        assert_eq!(e.to_string(), "inputs[0] is not a Device input");
        let e = set_calibration_matrix(KIOSK, 3, M).unwrap_err();
        assert_eq!(e.to_string(), "inputs[3] is not a Device input");
    }

    #[test]
    fn text_that_cannot_be_edited_safely_says_what_is_missing() {
        // `Device (` with a space and no calibration field: no `Device(` to add it after.
        let spaced = KIOSK
            .replace(KIOSK_CALIBRATION, "")
            .replace("Device(", "Device (");
        assert!(Config::from_str(&spaced, Path::new("s")).is_ok());
        let e = set_calibration_matrix(&spaced, 0, M).unwrap_err();
        assert!(matches!(e, EditError::CannotEdit { .. }), "{e:?}");
        assert_eq!(e.to_string(), "cannot find the Device input in the text");
        // Brackets in a comment inside the value: its end cannot be found.
        let commented = KIOSK.replace(
            "matrix: None",
            "matrix: Some(/* (((((((( */ (1, 0, 0, 0, 1, 0))",
        );
        assert!(Config::from_str(&commented, Path::new("c")).is_ok());
        let e = set_calibration_matrix(&commented, 0, M).unwrap_err();
        assert_eq!(e.to_string(), "unbalanced parentheses in matrix");
        // Every reason is printed as it is.
        for reason in [
            "no ':' after matrix",
            "no '(' after Some",
            "the matrix value is neither None nor Some(...)",
            "no '(' after calibration",
            "no inputs field",
        ] {
            assert_eq!(cannot_edit(reason).to_string(), reason);
        }
    }

    #[test]
    fn an_edit_that_leaves_an_invalid_config_is_refused() {
        let e = set_calibration_matrix(KIOSK, 0, [f64::NAN, 0.0, 0.0, 0.0, 1.0, 0.0]).unwrap_err();
        assert!(matches!(e, EditError::InvalidResult(_)), "{e:?}");
        let m = e.to_string();
        assert!(
            m.starts_with("the edited config is invalid: <edited>:"),
            "{m}"
        );
    }
}
