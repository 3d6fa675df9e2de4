//! No function of `src/` is over 80 lines (issue 78), from its `fn` line to its closing brace,
//! comments and the insides of string and character literals not read as braces.

use std::path::Path;

/// The longest a function of `src/` may be, in lines.
const MAX_LINES: usize = 80;

/// `text` with the contents of comments and literals (strings, raw strings, byte strings,
/// characters) blanked to spaces, its line breaks kept: what is left has only the code's own
/// braces.
fn blank_literals(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = b.to_vec();
    let blank = |out: &mut Vec<u8>, from: usize, to: usize| {
        for c in &mut out[from..to] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    let mut i = 0;
    while i < b.len() {
        let word_before = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        let end = if b[i..].starts_with(b"//") {
            b[i..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(b.len(), |n| i + n)
        } else if b[i..].starts_with(b"/*") {
            find(b, i + 2, b"*/").map_or(b.len(), |n| n + 2)
        } else if !word_before && raw_string_start(&b[i..]).is_some() {
            let (len, hashes) = raw_string_start(&b[i..]).unwrap();
            let mut close = vec![b'"'];
            close.extend(std::iter::repeat_n(b'#', hashes));
            find(b, i + len, &close).map_or(b.len(), |n| n + close.len())
        } else if b[i] == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            j + 1
        } else if b[i] == b'\'' {
            char_literal_len(&b[i..]).map_or(i + 1, |n| i + n)
        } else {
            i += 1;
            continue;
        };
        let end = end.min(b.len());
        blank(&mut out, i, end);
        i = end;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn find(b: &[u8], from: usize, what: &[u8]) -> Option<usize> {
    (from..b.len().saturating_sub(what.len() - 1)).find(|&j| b[j..].starts_with(what))
}

/// `r"`, `r#"`, `br##"`, …: the opening's length and its count of `#`.
fn raw_string_start(b: &[u8]) -> Option<(usize, usize)> {
    let r = usize::from(b.first() == Some(&b'b'));
    if b.get(r) != Some(&b'r') {
        return None;
    }
    let hashes = b[r + 1..].iter().take_while(|&&c| c == b'#').count();
    (b.get(r + 1 + hashes) == Some(&b'"')).then_some((r + 2 + hashes, hashes))
}

/// The length of a character literal at the start of `b` (`'a'`, `'\n'`, `'\u{1F600}'`, `'é'`),
/// `None` for a lifetime (`'a`).
fn char_literal_len(b: &[u8]) -> Option<usize> {
    let close = match b.get(1)? {
        b'\\' => b[2..].iter().position(|&c| c == b'\'').map(|n| n + 2)?,
        _ => (2..6.min(b.len())).find(|&j| {
            b[j] == b'\'' && std::str::from_utf8(&b[1..j]).is_ok_and(|s| s.chars().count() == 1)
        })?,
    };
    Some(close + 1)
}

/// Each function of `code` (literals blanked): its name, first line (1-based) and length in
/// lines, from its `fn` to its closing brace (a declaration without a body is none).
fn functions(code: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = code.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some(name) = fn_name(line) else { continue };
        let mut depth = 0i64;
        for (j, l) in lines.iter().enumerate().skip(i) {
            let opened = depth > 0;
            if depth == 0 && l.contains(';') && !l.contains('{') {
                break; // a declaration (a trait's method without a default)
            }
            depth += l.matches('{').count() as i64 - l.matches('}').count() as i64;
            if depth <= 0 && (opened || l.contains('{')) {
                out.push((name.to_string(), i + 1, j - i + 1));
                break;
            }
        }
    }
    out
}

/// The name of the function a line begins (`pub(crate) const fn name`), if it begins one.
fn fn_name(line: &str) -> Option<&str> {
    let mut words = line.split_whitespace();
    for w in words.by_ref() {
        let qualifier = w == "pub"
            || w.starts_with("pub(")
            || ["const", "async", "unsafe", "extern"].contains(&w);
        if w == "fn" {
            let name = words.next()?;
            let end = name
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(name.len());
            return (end > 0).then(|| &name[..end]);
        }
        if !qualifier && !w.starts_with('"') {
            return None;
        }
    }
    None
}

#[test]
fn no_function_is_over_80_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    super::rust_files(&root.join("src"), &mut files);
    files.sort();
    let mut long = Vec::new();
    let mut seen = 0;
    for f in &files {
        let code = blank_literals(&std::fs::read_to_string(f).unwrap());
        for (name, line, len) in functions(&code) {
            seen += 1;
            if len > MAX_LINES {
                let at = f.strip_prefix(root).unwrap().display();
                long.push(format!("{at}:{line} {name}: {len} lines"));
            }
        }
    }
    assert!(seen > 1000, "{seen} functions read");
    assert!(
        long.is_empty(),
        "functions over {MAX_LINES} lines:\n{}",
        long.join("\n")
    );
}

/// The reading sees what it must: braces in strings, raw strings, characters and comments are
/// not the code's, a lifetime is not a character, and a declaration has no body.
#[test]
fn function_lengths_are_read_past_literals() {
    let code = r##"
pub(crate) fn a<'x>(s: &'x str) -> char {
    let t = "}}}"; // }
    let r = r#"{"#;
    /* { */
    '{'
}
fn declared(x: u8);
const fn b() {}
"##;
    let found = functions(&blank_literals(code));
    assert_eq!(
        found,
        [("a".to_string(), 2, 6), ("b".to_string(), 9, 1)],
        "{}",
        blank_literals(code)
    );
}
