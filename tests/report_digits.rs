//! No number is typed in the report's prose (issue 33): every result, setting and constant that
//! `paper/report.tex` states comes from a generated file (`\res{…}` from
//! `paper/generated/numbers.tex` and `presets.tex`, `\setting{…}` from `settings.tex`). The
//! rule, also stated in `paper/README.md`: after removing
//!
//! 1. comments (an unescaped `%` to the end of its line),
//! 2. the commands of [`NAMED`] with their arguments (keys, labels, paths, options),
//! 3. `\texttt{…}`, which is code (a file, path, identifier or shell command whose digits belong
//!    to the name), except that a setting written `name = value` in it (spaces around `=`)
//!    keeps its content, to be checked,
//! 4. every [`ALLOWED`] name or notation, and every maze named by its size, `$N\times N$` (the
//!    same number twice),
//!
//! no digit may remain; each one left is printed with its line and its token.

use std::collections::BTreeSet;

/// Commands whose arguments are names, keys, paths or options, not prose: removed with their
/// arguments (`[…]` options and one `{…}`; `\begin` takes every argument that follows it, as in
/// `\begin{thebibliography}{9}`).
const NAMED: [&str; 13] = [
    "res",
    "path",
    "setting",
    "ref",
    "label",
    "cite",
    "bibitem",
    "input",
    "includegraphics",
    "usepackage",
    "documentclass",
    "begin",
    "end",
];

/// What may keep a digit in the prose, with why: names and notation, not quantities. Each entry
/// is an exact string, allowed where it does not continue a word or a number on either side
/// (`TD3` does not allow `TD35`).
const ALLOWED: &[(&str, &str)] = &[
    ("Phase~1", "the name of the paper's first phase"),
    ("Phase~2", "the name of the paper's second phase"),
    ("phase~1", "the name of the paper's first phase"),
    ("phase~2", "the name of the paper's second phase"),
    (
        "phase-1",
        "the name of the paper's first phase, as an adjective",
    ),
    ("Algorithm~1", "the name of the paper's Algorithm 1"),
    ("Algorithm~2", "the name of the paper's Algorithm 2"),
    ("Algorithm~3", "the name of the paper's Algorithm 3"),
    ("TD3", "the name of a learner"),
    ("SB3", "the name of a library (Stable-Baselines3)"),
    ("Stable-Baselines3", "the name of a library"),
    ("Pendulum-v1", "the name of gymnasium's task"),
    ("SHA-256", "the name of a hash function"),
    ("32-bit", "the name of a float type (f32)"),
    ("ICANN 2020", "the cited paper's venue and year"),
    ("s_0", "the name of the start state"),
    (
        "1/\\max(d(s), r)",
        "the potential's formula: one over the distance",
    ),
    (
        "1/r",
        "the potential's formula at the goal region's radius r",
    ),
    ("1/d(s)", "the potential's formula at distance d(s)"),
    (
        "K > 0",
        "the paper's loop bound on the index K (Algorithm 1)",
    ),
    (
        "K = 0",
        "the first index of tau, where Backplay's walk ends",
    ),
    (
        "\\alpha + 1",
        "one round more than alpha, in the paper's own parameter",
    ),
    (
        "2\\varepsilon",
        "the diameter of a ball of radius epsilon, in a formula",
    ),
    ("$-1$ per wall hit", "the paper's reward for a blocked step"),
    ("$+1$ at the target", "the paper's reward at the target"),
    (
        "]^2",
        "an interval squared: the plane of the two action axes",
    ),
    (
        "$[-1, 1]$",
        "the normalised action interval (SB3's, our goal-relative inputs')",
    ),
    (
        "$1/2$",
        "the claims' rule: an interval below or above one half of the runs",
    ),
    (
        "$x = 1$",
        "the performance profile's unit: the paper's own steps",
    ),
    ("performance of 100\\,\\%''", "a quotation of the paper"),
];

/// Each digit left in `text` (LaTeX) after the removals of the module's rule, as (line from 1,
/// the whitespace-delimited token holding it), one entry per token.
fn typed_numbers(text: &str) -> Vec<(usize, String)> {
    let mut chars: Vec<char> = strip_comments(text).chars().collect();
    for name in NAMED {
        remove_command(&mut chars, name);
    }
    remove_texttt(&mut chars);
    for (allowed, _) in ALLOWED {
        blank_allowed(&mut chars, allowed);
    }
    blank_maze_sizes(&mut chars);
    let mut out = Vec::new();
    let mut seen = BTreeSet::new();
    let mut line = 1;
    for i in 0..chars.len() {
        if chars[i] == '\n' {
            line += 1;
        }
        if !chars[i].is_ascii_digit() {
            continue;
        }
        let start = (0..i)
            .rev()
            .find(|&j| chars[j].is_whitespace())
            .map_or(0, |j| j + 1);
        let end = (i..chars.len())
            .find(|&j| chars[j].is_whitespace())
            .unwrap_or(chars.len());
        if seen.insert(start) {
            out.push((line, chars[start..end].iter().collect()));
        }
    }
    out
}

/// `text` without its comments: from an unescaped `%` (one preceded by an even number of
/// backslashes) to the end of its line.
fn strip_comments(text: &str) -> String {
    let mut out = String::new();
    for line in text.split_inclusive('\n') {
        let chars: Vec<char> = line.chars().collect();
        let mut cut = None;
        for (i, &c) in chars.iter().enumerate() {
            if c == '%' && chars[..i].iter().rev().take_while(|&&b| b == '\\').count() % 2 == 0 {
                cut = Some(i);
                break;
            }
        }
        match cut {
            Some(i) => {
                out.extend(&chars[..i]);
                if line.ends_with('\n') {
                    out.push('\n');
                }
            }
            None => out.push_str(line),
        }
    }
    out
}

/// Replaces `chars[from..to]` by spaces, keeping line breaks (so line numbers stay).
fn blank(chars: &mut [char], from: usize, to: usize) {
    for c in &mut chars[from..to] {
        if *c != '\n' {
            *c = ' ';
        }
    }
}

/// The end (exclusive) of the group opened by `open` at `chars[at]`, nested groups included;
/// the end of the text when it is never closed.
fn group_end(chars: &[char], at: usize, open: char, close: char) -> usize {
    let mut depth = 0;
    for (i, &c) in chars.iter().enumerate().skip(at) {
        if c == open && (i == 0 || chars[i - 1] != '\\') {
            depth += 1;
        } else if c == close && (i == 0 || chars[i - 1] != '\\') {
            depth -= 1;
            if depth == 0 {
                return i + 1;
            }
        }
    }
    chars.len()
}

/// The positions where the command `\name` starts (not a longer command's prefix).
fn command_starts(chars: &[char], name: &str) -> Vec<usize> {
    let pattern: Vec<char> = format!("\\{name}").chars().collect();
    (0..chars.len())
        .filter(|&i| {
            chars[i..].starts_with(&pattern)
                && chars
                    .get(i + pattern.len())
                    .is_none_or(|c| !c.is_ascii_alphabetic())
        })
        .collect()
}

/// Blanks every `\name[…]{…}` (for `\begin`, every argument that follows).
fn remove_command(chars: &mut [char], name: &str) {
    for start in command_starts(chars, name) {
        let mut at = start + name.len() + 1;
        let mut braces = 0;
        while let Some(&c) = chars.get(at) {
            if c == '[' && braces == 0 {
                at = group_end(chars, at, '[', ']');
            } else if c == '{' && (braces == 0 || name == "begin") {
                at = group_end(chars, at, '{', '}');
                braces += 1;
            } else {
                break;
            }
        }
        blank(chars, start, at);
    }
}

/// `\texttt{…}` is code: a file, path, identifier or shell command, whose digits belong to the
/// name; it is removed, unless it states a setting as `name = value` (with spaces around the
/// `=`, as the preset files write it), whose value is checked as prose.
fn remove_texttt(chars: &mut [char]) {
    for start in command_starts(chars, "texttt") {
        let open = start + "\\texttt".len();
        if chars.get(open) != Some(&'{') {
            continue;
        }
        let end = group_end(chars, open, '{', '}');
        let content: String = chars[open + 1..end.saturating_sub(1)].iter().collect();
        if content.contains(" = ") {
            blank(chars, start, open + 1);
            blank(chars, end - 1, end);
        } else {
            blank(chars, start, end);
        }
    }
}

/// Whether `c` would continue a word or a number next to an allowed string.
fn continues(c: Option<&char>) -> bool {
    c.is_some_and(|c| c.is_ascii_alphanumeric())
}

/// Blanks every occurrence of `allowed` that does not continue a word or number.
fn blank_allowed(chars: &mut [char], allowed: &str) {
    let pattern: Vec<char> = allowed.chars().collect();
    let mut i = 0;
    while i + pattern.len() <= chars.len() {
        let end = i + pattern.len();
        let fits = chars[i..end] == pattern[..]
            && !(pattern[0].is_ascii_alphanumeric() && i > 0 && continues(chars.get(i - 1)))
            && !(pattern[pattern.len() - 1].is_ascii_alphanumeric() && continues(chars.get(end)));
        if fits {
            blank(chars, i, end);
            i = end;
        } else {
            i += 1;
        }
    }
}

/// Blanks every `$N\times N$` (the same number twice): a maze named by its size.
fn blank_maze_sizes(chars: &mut [char]) {
    let times: Vec<char> = "\\times".chars().collect();
    let digits = |from: usize, chars: &[char]| {
        (from..chars.len())
            .find(|&j| !chars[j].is_ascii_digit())
            .unwrap_or(chars.len())
    };
    let mut i = 0;
    while i < chars.len() {
        if chars[i] == '$' {
            let a_end = digits(i + 1, chars);
            if a_end > i + 1 && chars[a_end..].starts_with(&times) {
                let b = a_end + times.len();
                let b_end = digits(b, chars);
                if chars[i + 1..a_end] == chars[b..b_end] && chars.get(b_end) == Some(&'$') {
                    blank(chars, i, b_end + 1);
                    i = b_end + 1;
                    continue;
                }
            }
        }
        i += 1;
    }
}

/// The report passes: no digit is typed in its prose; planted in it, one is found.
#[test]
fn the_report_types_no_number() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/paper/report.tex");
    let text = std::fs::read_to_string(path).expect("paper/report.tex");
    let found = typed_numbers(&text);
    assert!(
        found.is_empty(),
        "paper/report.tex types {} number(s) in its prose; quote a generated one (\\res{{…}}, \
         \\setting{{…}}) or rephrase (the rule and the allow-list: paper/README.md):\n{}",
        found.len(),
        found
            .iter()
            .map(|(line, token)| format!("  line {line}: {token}"))
            .collect::<Vec<_>>()
            .join("\n")
    );
    // The same text with one typed number planted after a heading fails, at that line.
    let heading = "\\section{The results table}";
    let line = text
        .lines()
        .position(|l| l == heading)
        .expect("the heading")
        + 2;
    let planted = text.replacen(heading, &format!("{heading}\nIt took 42 seconds."), 1);
    assert_eq!(typed_numbers(&planted), vec![(line, "42".to_string())]);
}

/// The check finds a planted number, with its line, and nothing in a text of names, notation
/// and generated numbers; a number in a comment or a `\texttt` name does not count, a setting
/// stated as `name = value` in `\texttt` does.
#[test]
fn the_check_finds_a_typed_number_and_its_line() {
    let clean = "\\section{Set-up}\n\
        Phase~1 on the $15\\times15$ maze took \\res{table:pbcs-maze15:median} steps\n\
        (\\texttt{results/raw/table/pbcs-maze15/s3.csv}; TD3 from $B_\\varepsilon(s_0)$).\n\
        % typed in a comment: 42\n\
        \\texttt{max\\_rounds = \\res{preset:fast:phase2.max_rounds}}, solved at\n\
        \\res{code:solved_at_percent}\\,\\% (an escaped \\% is no comment).\n";
    assert!(typed_numbers(clean).is_empty(), "{clean}");
    let planted = clean.replace(
        "took \\res{table:pbcs-maze15:median} steps",
        "took 42 seconds",
    );
    assert_eq!(typed_numbers(&planted), vec![(2, "42".to_string())]);
    let percent = clean.replace("\\res{code:solved_at_percent}", "95");
    assert_eq!(typed_numbers(&percent), vec![(6, "95\\,\\%".to_string())]);
    let setting = clean.replace("\\res{preset:fast:phase2.max_rounds}", "3");
    assert_eq!(typed_numbers(&setting), vec![(5, "3".to_string())]);
    // A maze size is a name only as $N\times N$ with the same N.
    assert_eq!(
        typed_numbers("a $15\\times16$ maze, 7\\% of it"),
        vec![(1, "$15\\times16$".to_string()), (1, "7\\%".to_string())]
    );
    // An allowed name does not cover a longer one.
    assert_eq!(
        typed_numbers("TD3 and TD35, Phase~12"),
        vec![(1, "TD35,".to_string()), (1, "Phase~12".to_string())]
    );
}

/// Every allowed entry keeps a digit (an entry without one would allow nothing) and says why.
#[test]
fn every_allowed_entry_holds_a_digit_and_a_reason() {
    for (allowed, why) in ALLOWED {
        assert!(allowed.chars().any(|c| c.is_ascii_digit()), "{allowed}");
        assert!(!why.is_empty(), "{allowed}");
    }
}
