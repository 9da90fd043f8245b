//! Hex bytes as hid-recorder writes them (`R:` descriptor lines, `E:` reports).

/// Parses hex byte tokens (`05 0d 09`), appending them to `out`; returns how many.
pub(crate) fn parse_hex_bytes<'a>(
    tokens: impl Iterator<Item = &'a str>,
    out: &mut Vec<u8>,
) -> Result<usize, String> {
    let mut n = 0;
    for tok in tokens {
        let bad = || format!("`{}` is not a hex byte", crate::located::Escaped(tok));
        if tok.is_empty() || tok.len() > 2 {
            return Err(bad());
        }
        let b = u8::from_str_radix(tok, 16).map_err(|_| bad())?;
        out.push(b);
        n += 1;
    }
    Ok(n)
}

/// Parses what follows `R:`: a byte count, then that many hex bytes.
pub(crate) fn parse_r_line(rest: &str) -> Result<Vec<u8>, String> {
    let mut it = rest.split_whitespace();
    let len: usize = it
        .next()
        .ok_or("empty R: line")?
        .parse()
        .map_err(|_| "R: must start with the descriptor's byte count".to_string())?;
    let mut out = Vec::with_capacity(len.min(4096));
    let n = parse_hex_bytes(it, &mut out)?;
    if n != len {
        return Err(format!(
            "R: announces {len} bytes but holds {n} (truncated or wrapped line?)"
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn r_line() {
        assert_eq!(parse_r_line(" 3 05 0d 09"), Ok(vec![5, 0x0d, 9]));
        assert!(parse_r_line(" 4 05 0d 09")
            .unwrap_err()
            .contains("announces 4"));
        assert!(parse_r_line(" 1 zz").is_err());
    }
}
