//! Math spans in the prose of our TOML files (`experiments/settings.toml`, `departures.toml`,
//! `claims.toml`): formulas written `$…$` with Unicode inside (`$d(s′, τ_T) ≤ ε$`). Their
//! loaders check them ([`check_math`]), so a slip is an error naming the entry, not a LaTeX
//! failure; the report sets them as math (`crate::report::tex`) and Markdown drops the dollars
//! ([`plain`]). A module of its own: the claims and the report both read it.

/// The text without its math spans' dollars (`$B_ε(τ_N)$` → `B_ε(τ_N)`): what a Markdown table
/// or a terminal shows. An unbalanced last `$` is kept.
pub fn plain(text: &str) -> String {
    let pieces: Vec<&str> = text.split('$').collect();
    if pieces.len() % 2 == 1 {
        pieces.concat()
    } else {
        let (last, rest) = pieces.split_last().expect("split yields a piece");
        format!("{}${last}", rest.concat())
    }
}

/// Checks the math spans of a text: every `$` has its closing one, no span is empty, the braces
/// of each span are balanced, no span ends in `_` or `^`, and none holds a backslash (a span is
/// written in Unicode, `α`, not `\alpha`). The error says what is wrong and where (the
/// character's position, from 1); the loaders add the file, the entry and the field.
pub fn check_math(text: &str) -> Result<(), String> {
    let dollars: Vec<usize> = text
        .chars()
        .enumerate()
        .filter(|(_, c)| *c == '$')
        .map(|(i, _)| i + 1)
        .collect();
    if dollars.len() % 2 == 1 {
        return Err(format!(
            "unbalanced `$`: the math span opened at character {} is never closed (a math span \
             is `$…$`)",
            dollars[dollars.len() - 1]
        ));
    }
    for (pair, span) in dollars.chunks(2).zip(text.split('$').skip(1).step_by(2)) {
        let at = pair[0];
        if span.trim().is_empty() {
            return Err(format!("an empty math span `$$` at character {at}"));
        }
        if span.contains('\\') {
            return Err(format!(
                "the math span `${span}$` at character {at} holds a backslash: write the \
                 symbols in Unicode (`α`, `≤`), not as LaTeX commands"
            ));
        }
        let mut depth = 0_i32;
        for c in span.chars() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                _ => {}
            }
            if depth < 0 {
                break;
            }
        }
        if depth != 0 {
            return Err(format!(
                "the math span `${span}$` at character {at} has unbalanced braces"
            ));
        }
        if span.trim_end().ends_with(['_', '^']) {
            return Err(format!(
                "the math span `${span}$` at character {at} ends in a subscript or superscript \
                 mark"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_text_drops_the_dollars() {
        assert_eq!(plain("$d(s′, τ_T) ≤ ε$ or not"), "d(s′, τ_T) ≤ ε or not");
        assert_eq!(plain("no math"), "no math");
        assert_eq!(plain("$a$ and $b"), "a and $b");
    }

    #[test]
    fn unbalanced_dollars_and_other_slips_are_errors() {
        let e = check_math("$d(s′, τ_T) ≤ ε$ or $B_ε").unwrap_err();
        assert!(
            e.contains("unbalanced `$`") && e.contains("character 21"),
            "{e}"
        );
        assert!(check_math("a $$ b")
            .unwrap_err()
            .contains("empty math span"));
        assert!(check_math("$A_{i+1$")
            .unwrap_err()
            .contains("unbalanced braces"));
        assert!(check_math("$x}{$")
            .unwrap_err()
            .contains("unbalanced braces"));
        assert!(check_math("$x_$").unwrap_err().contains("subscript"));
        assert!(check_math("$\\alpha$").unwrap_err().contains("backslash"));
        assert_eq!(check_math("$a$, $B_ε(τ_N)$ and text"), Ok(()));
        assert_eq!(check_math("no math"), Ok(()));
    }
}
