//! Fortran-formatted fields: fixed columns for records whose text fields may hold blanks, and a
//! tolerant number stream for data records.
//!
//! Numbers accept Fortran `D` exponents (`1.0D+03`) and exponents without the letter
//! (`1.0+003`, written by some Fortran runtimes when the exponent has three digits). Data records
//! are read as a stream of numbers regardless of how many sit on a line (writers differ), and two
//! numbers glued by a full-width field (`-1.23456e-05-2.34567e-05`) are split at the sign.

use crate::error::{UffError, syntax};

/// Parses one number, Fortran style. `None` if it is not a finite number.
pub fn parse_f64(s: &str) -> Option<f64> {
    let t = s.trim();
    if t.is_empty() {
        return None;
    }
    let v = match t.parse::<f64>() {
        Ok(v) => v,
        Err(_) => {
            let fixed: String = t
                .chars()
                .map(|c| if c == 'D' || c == 'd' { 'E' } else { c })
                .collect();
            match fixed.parse::<f64>() {
                Ok(v) => v,
                // 1.0+003: a sign after a digit starts the exponent.
                Err(_) => {
                    let b = fixed.as_bytes();
                    let pos = (1..b.len())
                        .find(|&i| (b[i] == b'+' || b[i] == b'-') && b[i - 1].is_ascii_digit())?;
                    format!("{}E{}", &fixed[..pos], &fixed[pos..])
                        .parse()
                        .ok()?
                }
            }
        }
    };
    v.is_finite().then_some(v)
}

/// The characters [a, b) of a line (fewer at its end, empty beyond it).
pub fn cols(line: &str, a: usize, b: usize) -> &str {
    let n = line.len();
    if !line.is_char_boundary(a.min(n)) || !line.is_char_boundary(b.min(n)) {
        return "";
    }
    &line[a.min(n)..b.min(n)]
}

/// An integer field; blank reads as `blank`.
pub fn int_field(
    line: &str,
    a: usize,
    b: usize,
    blank: i64,
    at: usize,
    what: &str,
) -> Result<i64, UffError> {
    let t = cols(line, a, b).trim();
    if t.is_empty() {
        return Ok(blank);
    }
    t.parse()
        .map_err(|_| syntax(at, format!("{what}: '{t}' is not an integer")))
}

/// All whitespace-separated integers of a line.
pub fn ints(line: &str, at: usize, what: &str) -> Result<Vec<i64>, UffError> {
    line.split_whitespace()
        .map(|t| {
            t.parse::<i64>()
                .map_err(|_| syntax(at, format!("{what}: '{t}' is not an integer")))
        })
        .collect()
}

/// Exactly `n` integers at the start of a line (more are ignored).
pub fn ints_n(line: &str, n: usize, at: usize, what: &str) -> Result<Vec<i64>, UffError> {
    let v = ints(line, at, what)?;
    if v.len() < n {
        return Err(syntax(
            at,
            format!("{what}: expected {n} integers, found {}", v.len()),
        ));
    }
    Ok(v[..n].to_vec())
}

/// Splits a token of glued numbers at signs that start a new number: a sign after a digit or a
/// point, unless what follows it is a bare exponent (up to three digits, as in `1.0-100`).
fn split_glued(tok: &str) -> Vec<&str> {
    let b = tok.as_bytes();
    let mut parts = Vec::new();
    let mut start = 0;
    for i in 1..b.len() {
        if (b[i] == b'-' || b[i] == b'+') && (b[i - 1].is_ascii_digit() || b[i - 1] == b'.') {
            let rest = &b[i + 1..];
            let end = rest
                .iter()
                .position(|c| *c == b'-' || *c == b'+')
                .unwrap_or(rest.len());
            let bare_exponent = end <= 3
                && end > 0
                && rest[..end].iter().all(u8::is_ascii_digit)
                && !tok[start..i].contains(['E', 'e', 'D', 'd']);
            if !bare_exponent {
                parts.push(&tok[start..i]);
                start = i;
            }
        }
    }
    parts.push(&tok[start..]);
    parts
}

/// Reads all numbers of `lines` in order; errors name the line.
pub fn numbers(lines: &[(usize, String)], out: &mut Vec<f64>) -> Result<(), UffError> {
    for (at, line) in lines {
        for tok in line.split_whitespace() {
            match parse_f64(tok) {
                Some(v) => out.push(v),
                None => {
                    for part in split_glued(tok) {
                        let v = parse_f64(part).ok_or_else(|| {
                            syntax(*at, format!("'{part}' is not a finite number"))
                        })?;
                        out.push(v);
                    }
                }
            }
        }
    }
    Ok(())
}

/// The line at `i` of a dataset's records, or an error naming the record that is missing.
pub fn record<'a>(
    lines: &'a [(usize, String)],
    i: usize,
    after: usize,
    what: &str,
) -> Result<(usize, &'a str), UffError> {
    lines.get(i).map(|(n, s)| (*n, s.as_str())).ok_or_else(|| {
        syntax(
            lines.last().map_or(after, |l| l.0),
            format!("the dataset ends before {what}"),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fortran_numbers() {
        assert_eq!(parse_f64("1.00000000000000000D+03"), Some(1e3));
        assert_eq!(parse_f64(" -2.5E-01 "), Some(-0.25));
        assert_eq!(parse_f64("1.0+003"), Some(1e3));
        assert_eq!(parse_f64("1.0-003"), Some(1e-3));
        assert_eq!(parse_f64("NaN"), None);
        assert_eq!(parse_f64("abc"), None);
    }

    #[test]
    fn glued_numbers_split_at_signs() {
        let mut v = Vec::new();
        numbers(&[(3, "-1.23456e-05-2.34567e+05 1.0".into())], &mut v).unwrap();
        assert_eq!(v, vec![-1.23456e-05, -2.34567e+05, 1.0]);
        v.clear();
        numbers(
            &[(3, "-0.00115633-6.31809E-004 2.5-003-1.0".into())],
            &mut v,
        )
        .unwrap();
        assert_eq!(v, vec![-0.00115633, -6.31809E-004, 2.5e-3, -1.0]);
        let e = numbers(&[(7, "1.0 x2".into())], &mut v).unwrap_err();
        assert_eq!(e.to_string(), "line 7: 'x2' is not a finite number");
    }
}
