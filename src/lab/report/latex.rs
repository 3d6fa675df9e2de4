//! Text into pdflatex's LaTeX: the labels, settings, claims and departures the generated tables
//! quote are written in Unicode; pdflatex's `utf8` input encoding knows few of its symbols.
//!
//! The prose of `experiments/settings.toml`, `departures.toml` and `claims.toml` marks formulas
//! as math spans, `$…$` with Unicode inside (`$d(s′, τ_T) ≤ ε$`): [`tex`] sets a span as math
//! (`_`, `^` and `{…}` are subscripts, superscripts and groups there);
//! [`crate::mathtext::plain`] drops the dollars for a Markdown or terminal reader, and
//! [`crate::mathtext::check_math`] is what the files' loaders ask of every such text, so that a
//! slip is an error naming the entry, not a LaTeX failure.

use std::fmt::Write as _;

/// Escapes text for LaTeX (pdflatex). Outside math spans: LaTeX's special characters are
/// escaped, Greek letters and symbols become inline math, a lone letter with a subscript
/// (`τ_K`, `B_ε`, `s_0`, `A_{i+1}`, the labels' notation) is set as math, a path of the
/// repository (`experiments/ablations.toml`) as `\path{…}` (the url package's, which may break it),
/// a Markdown code span (`` `make bench` ``) as `\texttt{…}`, and straight double quotes
/// become opening and closing quotes. Inside a span `$…$`: math,
/// with Greek letters as `\alpha`…, symbols as their commands (`≤` → `\le`, `′` → `'`, `−` →
/// `-`), words of two letters or more upright (`max` → `\max`, `goal` → `\mathrm{goal}`). An
/// unbalanced last `$` is written as a dollar sign (the loaders refuse it first:
/// [`crate::mathtext::check_math`]).
pub fn tex(text: &str) -> String {
    let mut out = String::new();
    let pieces: Vec<&str> = text.split('$').collect();
    let balanced = pieces.len() % 2 == 1;
    for (i, piece) in pieces.iter().enumerate() {
        if !balanced && i == pieces.len() - 1 {
            out.push_str("\\$");
            text_tex(piece, false, &mut out);
        } else if i % 2 == 1 {
            if !piece.is_empty() {
                out.push('$');
                math_tex(piece, &mut out);
                out.push('$');
            }
        } else {
            text_tex(piece, false, &mut out);
        }
    }
    out
}

/// Escapes code for `\texttt{…}` (a field name, a preset's value, a claim's id): every
/// character as written (`$` and `_` escaped, no math spans, no subscripts), Greek letters and
/// symbols as inline math.
pub fn tex_code(text: &str) -> String {
    let mut out = String::new();
    text_tex(text, true, &mut out);
    out
}

/// [`tex_code`] in `\texttt{…}` that may break after a `_`, a `/` or a `.` before a letter
/// (`phase2.chain_verify_episodes`, `success_region`): for a narrow column of a table.
pub fn tex_code_breakable(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::from("\\texttt{");
    for (i, &c) in chars.iter().enumerate() {
        text_tex(&c.to_string(), true, &mut out);
        let letter_follows = chars.get(i + 1).is_some_and(char::is_ascii_alphabetic);
        if c == '_' || c == '/' || (c == '.' && letter_follows) {
            out.push_str("\\allowbreak{}");
        }
    }
    out.push('}');
    out
}

/// The top folders of the repository: a word that starts with one of them and a `/` is a path.
const ROOTS: [&str; 11] = [
    "experiments",
    "results",
    "src",
    "paper",
    "python",
    "tests",
    "scripts",
    "figures",
    "docs",
    "benches",
    "examples",
];

/// Text outside math spans (or, with `code`, every character as written).
fn text_tex(text: &str, code: bool, out: &mut String) {
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let prev = i.checked_sub(1).map(|j| chars[j]);
        let word_start = prev.is_none_or(|p| !is_word(p));
        if !code && prev.is_none_or(|p| p.is_whitespace() || p == '(') {
            if let Some(n) = path_len(&chars[i..]) {
                let path: String = chars[i..i + n].iter().collect();
                let _ = write!(out, "\\path{{{path}}}");
                i += n;
                continue;
            }
        }
        if !code && c == '`' {
            if let Some(n) = chars[i + 1..].iter().position(|&c| c == '`') {
                let inside: String = chars[i + 1..i + 1 + n].iter().collect();
                let _ = write!(out, "\\texttt{{{}}}", tex_code(&inside));
                i += n + 2;
                continue;
            }
        }
        if !code && word_start && is_letter(c) {
            if let Some(n) = subscript_len(&chars[i + 1..]) {
                let formula: String = chars[i..=i + n].iter().collect();
                out.push('$');
                math_tex(&formula, out);
                out.push('$');
                i += n + 1;
                continue;
            }
        }
        if let Some(name) = greek(c) {
            let _ = write!(out, "$\\{name}$");
            i += 1;
            continue;
        }
        if let Some(d) = subscript_digit(c) {
            let _ = write!(out, "$_{d}$");
            i += 1;
            continue;
        }
        match c {
            '\\' => out.push_str("\\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            '"' if !code => {
                let opens = prev.is_none_or(|p| p.is_whitespace() || p == '(');
                out.push_str(if opens { "``" } else { "''" });
            }
            '~' => out.push_str("\\textasciitilde{}"),
            '^' => out.push_str("\\textasciicircum{}"),
            '±' => out.push_str("$\\pm$"),
            '×' => out.push_str("$\\times$"),
            '·' => out.push_str("$\\cdot$"),
            '–' => out.push_str("--"),
            '—' => out.push_str("---"),
            '…' => out.push_str("\\dots{}"),
            '≤' => out.push_str("$\\le$"),
            '≥' => out.push_str("$\\ge$"),
            '≠' => out.push_str("$\\ne$"),
            '≈' => out.push_str("$\\approx$"),
            '∈' => out.push_str("$\\in$"),
            '∞' => out.push_str("$\\infty$"),
            '−' => out.push_str("$-$"),
            'µ' => out.push_str("\\textmu{}"),
            '′' => out.push_str("$'$"),
            '⌈' => out.push_str("$\\lceil$"),
            '⌉' => out.push_str("$\\rceil$"),
            '²' => out.push_str("$^2$"),
            '→' => out.push_str("$\\to$"),
            _ => out.push(c),
        }
        i += 1;
    }
}

/// The inside of a math span.
fn math_tex(text: &str, out: &mut String) {
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        // A control word: a space before a following letter keeps it apart (`\tau K`).
        let word = |out: &mut String, name: &str, next: usize| {
            out.push('\\');
            out.push_str(name);
            if chars.get(next).is_some_and(char::is_ascii_alphabetic) {
                out.push(' ');
            }
        };
        if c.is_ascii_alphabetic() {
            let n = chars[i..]
                .iter()
                .take_while(|c| c.is_ascii_alphabetic())
                .count();
            let run: String = chars[i..i + n].iter().collect();
            if n == 1 {
                out.push_str(&run);
            } else if OPERATORS.contains(&run.as_str()) {
                word(out, &run, i + n);
            } else {
                let _ = write!(out, "\\mathrm{{{run}}}");
            }
            i += n;
            continue;
        }
        if let Some(name) = greek(c) {
            word(out, name, i + 1);
            i += 1;
            continue;
        }
        if let Some(d) = subscript_digit(c) {
            let _ = write!(out, "_{d}");
            i += 1;
            continue;
        }
        let name = match c {
            '≤' => "le",
            '≥' => "ge",
            '≠' => "ne",
            '≈' => "approx",
            '∈' => "in",
            '±' => "pm",
            '×' => "times",
            '·' => "cdot",
            '→' => "to",
            '⌈' => "lceil",
            '⌉' => "rceil",
            '∞' => "infty",
            '…' => "dots",
            '~' => "sim",
            '\\' => "backslash",
            _ => "",
        };
        if !name.is_empty() {
            word(out, name, i + 1);
            i += 1;
            continue;
        }
        match c {
            '′' => out.push('\''),
            '−' | '–' => out.push('-'),
            '²' => out.push_str("^2"),
            '&' | '%' | '#' => {
                out.push('\\');
                out.push(c);
            }
            _ => out.push(c),
        }
        i += 1;
    }
}

/// The words that math sets as operators (`\max`); other words of two letters or more are
/// set upright with `\mathrm`.
const OPERATORS: [&str; 12] = [
    "max", "min", "arg", "log", "exp", "sup", "inf", "lim", "sin", "cos", "det", "dim",
];

/// A letter or digit of a word (Greek included), or `_`.
fn is_word(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// A Latin or Greek letter.
fn is_letter(c: char) -> bool {
    c.is_ascii_alphabetic() || greek(c).is_some()
}

/// The length of a subscript at the start of `rest` (`_K`, `_ε`, `_0`, `_{i+1}`), counting the
/// `_`: a single letter or digit that does not go on into a word (`_step` is no subscript),
/// or a braced group without `$`.
fn subscript_len(rest: &[char]) -> Option<usize> {
    if rest.first() != Some(&'_') {
        return None;
    }
    match rest.get(1)? {
        '{' => {
            let close = rest.iter().position(|&c| c == '}')?;
            let inside = &rest[2..close];
            (!inside.is_empty() && !inside.iter().any(|&c| matches!(c, '$' | '{' | '\\')))
                .then_some(close + 1)
        }
        &c if c.is_ascii_alphanumeric() || greek(c).is_some() => {
            (!rest.get(2).is_some_and(|&n| is_word(n))).then_some(2)
        }
        _ => None,
    }
}

/// The length of a repository path at the start of `rest` (`experiments/ablations.toml`,
/// `results/tables/*.timing.csv`), without a full stop that ends the sentence.
fn path_len(rest: &[char]) -> Option<usize> {
    let root = ROOTS.iter().find(|root| {
        let n = root.chars().count();
        rest.len() > n + 1
            && rest[..n].iter().copied().eq(root.chars())
            && rest[n] == '/'
            && is_path_char(rest[n + 1])
    })?;
    let mut n = rest.iter().take_while(|c| is_path_char(**c)).count();
    while n > 0 && matches!(rest[n - 1], '.' | '-') {
        n -= 1;
    }
    (n > root.len() + 1).then_some(n)
}

/// A character `\path` takes as it is inside an argument.
fn is_path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '/' | '.' | '_' | '-' | '*')
}

/// `₀`…`₉` as their digit.
fn subscript_digit(c: char) -> Option<char> {
    let d = (c as u32).checked_sub('₀' as u32)?;
    (d < 10).then(|| char::from_digit(d, 10)).flatten()
}

/// The LaTeX name of a Greek letter (`Φ` → `Phi`, `ε` → `varepsilon` as the paper writes it),
/// for the letters math mode has: pdflatex's `utf8` input encoding defines none of them.
fn greek(c: char) -> Option<&'static str> {
    const LOWER: [&str; 25] = [
        "alpha",
        "beta",
        "gamma",
        "delta",
        "varepsilon",
        "zeta",
        "eta",
        "theta",
        "iota",
        "kappa",
        "lambda",
        "mu",
        "nu",
        "xi",
        "",
        "pi",
        "rho",
        "varsigma",
        "sigma",
        "tau",
        "upsilon",
        "phi",
        "chi",
        "psi",
        "omega",
    ];
    const UPPER: [(char, &str); 11] = [
        ('Γ', "Gamma"),
        ('Δ', "Delta"),
        ('Θ', "Theta"),
        ('Λ', "Lambda"),
        ('Ξ', "Xi"),
        ('Π', "Pi"),
        ('Σ', "Sigma"),
        ('Υ', "Upsilon"),
        ('Φ', "Phi"),
        ('Ψ', "Psi"),
        ('Ω', "Omega"),
    ];
    let lower = (c as u32)
        .checked_sub('α' as u32)
        .and_then(|i| LOWER.get(i as usize));
    lower
        .copied()
        .filter(|name| !name.is_empty())
        .or_else(|| UPPER.iter().find(|(u, _)| *u == c).map(|(_, name)| *name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn greek_letters_become_math_and_specials_are_escaped() {
        assert_eq!(tex("Φ(s) = 1/d"), "$\\Phi$(s) = 1/d");
        assert_eq!(
            tex("σ, θ, ε, ς, ω"),
            "$\\sigma$, $\\theta$, $\\varepsilon$, $\\varsigma$, $\\omega$"
        );
        assert_eq!(tex("±0.1 & 5 %"), "$\\pm$0.1 \\& 5 \\%");
        assert_eq!(
            tex("# ~ ^ \\ { }"),
            "\\# \\textasciitilde{} \\textasciicircum{} \\textbackslash{} \\{ \\}"
        );
    }

    /// A math span is set as math: Greek letters as commands without nested dollars,
    /// subscripts, superscripts and groups kept, symbols as their commands, words upright.
    #[test]
    fn math_spans_become_math() {
        assert_eq!(
            tex("$d(s′, τ_T) ≤ ε$"),
            "$d(s', \\tau_T) \\le \\varepsilon$"
        );
        assert_eq!(tex("$(K_s, π_s)$"), "$(K_s, \\pi_s)$");
        assert_eq!(tex("$B_ε(τ_N)$"), "$B_\\varepsilon(\\tau_N)$");
        assert_eq!(tex("$A_{i+1}$"), "$A_{i+1}$");
        assert_eq!(
            tex("$Φ(s) = 1 / max(d, r)$"),
            "$\\Phi(s) = 1 / \\max(d, r)$"
        );
        assert_eq!(tex("$s − goal$"), "$s - \\mathrm{goal}$");
        assert_eq!(tex("$[−1, 1]²$"), "$[-1, 1]^2$");
        assert_eq!(tex("$τK$ $αβ$"), "$\\tau K$ $\\alpha\\beta$");
        assert_eq!(
            tex("$⌈p (L + 2ε) / 0.1⌉$"),
            "$\\lceil p (L + 2\\varepsilon) / 0.1\\rceil$"
        );
        assert_eq!(tex("$x ∈ B$, $x^2$"), "$x \\in B$, $x^2$");
        assert_eq!(tex("$s₀$"), "$s_0$");
    }

    /// Text and math side by side: outside a span, Greek letters are inline math and `_` is an
    /// underscore unless it is a lone letter's subscript.
    #[test]
    fn greek_inside_and_outside_math() {
        assert_eq!(
            tex("the ε-ball $B_ε(τ_K)$ of radius ε"),
            "the $\\varepsilon$-ball $B_\\varepsilon(\\tau_K)$ of radius $\\varepsilon$"
        );
        assert_eq!(tex("starts exactly at τ_K"), "starts exactly at $\\tau_K$");
        assert_eq!(
            tex("uniform in B_ε(τ_K), from s_0 to A_{i+1}"),
            "uniform in $B_\\varepsilon$($\\tau_K$), from $s_0$ to $A_{i+1}$"
        );
        assert_eq!(tex("from s₀"), "from s$_0$");
        // Names are not subscripts: the letter begins a word, or the subscript goes on.
        assert_eq!(tex("fast, adaptive_k off"), "fast, adaptive\\_k off");
        assert_eq!(tex("phase2.k_step"), "phase2.k\\_step");
        assert_eq!(tex("pointmaze_umaze"), "pointmaze\\_umaze");
        assert_eq!(tex("x_y_z"), "x\\_y\\_z");
    }

    #[test]
    fn paths_break_and_quotes_open_and_close() {
        assert_eq!(
            tex("experiments/ablations.toml, mazes 2 and 5"),
            "\\path{experiments/ablations.toml}, mazes 2 and 5"
        );
        assert_eq!(
            tex("(results/dev/issue24). See results/tables/*.timing.csv."),
            "(\\path{results/dev/issue24}). See \\path{results/tables/*.timing.csv}."
        );
        assert_eq!(tex("1/d and and/or"), "1/d and and/or");
        assert_eq!(
            tex("measured by `make bench` (ab_cd)"),
            "measured by \\texttt{make bench} (ab\\_cd)"
        );
        assert_eq!(tex("a ` alone"), "a ` alone");
        assert_eq!(
            tex("\"until performance stabilizes\", α"),
            "``until performance stabilizes'', $\\alpha$"
        );
    }

    #[test]
    fn breakable_code_breaks_after_underscores_slashes_and_dots_before_letters() {
        assert_eq!(
            tex_code_breakable("phase2.chain_verify"),
            "\\texttt{phase2.\\allowbreak{}chain\\_\\allowbreak{}verify}"
        );
        assert_eq!(tex_code_breakable("0.001"), "\\texttt{0.001}");
        assert_eq!(tex_code_breakable("64, 64"), "\\texttt{64, 64}");
    }

    /// Code is written as it is: no spans, no subscripts, no paths.
    #[test]
    fn code_is_escaped_as_written() {
        assert_eq!(tex_code("phase2.k_step"), "phase2.k\\_step");
        assert_eq!(tex_code("τ_K $x$"), "$\\tau$\\_K \\$x\\$");
        assert_eq!(tex_code("results/dev"), "results/dev");
    }

    #[test]
    fn unbalanced_dollars_are_an_error_and_a_dollar_sign() {
        assert!(crate::mathtext::check_math("$d(s′, τ_T) ≤ ε$ or $B_ε").is_err());
        // Were one to slip through, it is a dollar sign, not an open math mode.
        assert_eq!(tex("$a$ and $b"), "$a$ and \\$b");
        assert_eq!(tex("costs $5"), "costs \\$5");
    }

    /// Every letter of the Greek block that math mode has is mapped, and only those: omicron
    /// (no `\omicron`) and the capitals that look Latin are left alone.
    #[test]
    fn every_greek_letter_with_a_math_name_is_mapped() {
        let lower = ('α'..='ω')
            .filter(|c| greek(*c).is_none())
            .collect::<String>();
        assert_eq!(lower, "ο");
        let upper = ('Α'..='Ω').filter_map(greek).count();
        assert_eq!(upper, 11);
        assert_eq!(greek('A'), None);
    }
}
