//! Text mutation of generated RON, shared by the structure-aware targets: after a value is
//! generated and serialised, the rest of the input may cut, repeat, insert or overwrite
//! spans of the text, so inputs near valid files (one token off) are tried as well.

use libfuzzer_sys::arbitrary::Unstructured;

/// Tokens worth inserting into RON text: punctuation, literals at the edges of the
/// numeric types, and the words the schemas use are added by the caller.
const COMMON: &[&str] = &[
    "(",
    ")",
    "[",
    "]",
    "{",
    "}",
    ",",
    ":",
    "\"",
    "Some(",
    "None",
    "true",
    "false",
    "0",
    "-1",
    "1e39",
    "-1e39",
    "1e-45",
    "NaN",
    "inf",
    "-inf",
    "-0.0",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "//",
    "/*",
    "r#\"",
];

/// Applies up to four edits driven by `u` to `text`. Edits land on char boundaries.
pub fn mutate(u: &mut Unstructured, mut text: String, words: &[&str]) -> String {
    let edits: u8 = u.int_in_range(0..=4).unwrap_or(0);
    for _ in 0..edits {
        if text.is_empty() {
            break;
        }
        let at = boundary(&text, u.int_in_range(0..=text.len()).unwrap_or(0));
        let to = boundary(&text, at.saturating_add(u.int_in_range(0..=16).unwrap_or(0)).min(text.len()));
        match u.int_in_range(0..=4u8).unwrap_or(0) {
            // Cut a span.
            0 => text.replace_range(at..to, ""),
            // Cut the tail (a truncated file).
            1 => text.truncate(at),
            // Insert a token.
            2 | 3 => {
                let pool = if u.arbitrary::<bool>().unwrap_or(false) { COMMON } else { words };
                let tok = u.choose(pool).copied().unwrap_or(",");
                text.insert_str(at, tok);
            }
            // Repeat a span (duplicated fields, long lists).
            _ => {
                let span = text[at..to].to_string();
                let times = u.int_in_range(1..=64usize).unwrap_or(1);
                text.insert_str(to, &span.repeat(times));
            }
        }
    }
    text
}

fn boundary(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}
