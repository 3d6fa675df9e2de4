//! Text into pdflatex's LaTeX: the labels, settings and departures the generated tables quote
//! are written in Unicode; pdflatex's `utf8` input encoding knows few of its symbols.

use std::fmt::Write as _;

/// Escapes text for LaTeX (pdflatex): special characters, and the Greek letters and symbols
/// our labels use.
pub fn tex(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        if let Some(name) = greek(c) {
            let _ = write!(out, "$\\{name}$");
            continue;
        }
        match c {
            '\\' => out.push_str("\\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            '~' => out.push_str("\\textasciitilde{}"),
            '^' => out.push_str("\\textasciicircum{}"),
            '±' => out.push_str("$\\pm$"),
            '×' => out.push_str("$\\times$"),
            '·' => out.push_str("$\\cdot$"),
            '–' => out.push_str("--"),
            '—' => out.push_str("---"),
            '≤' => out.push_str("$\\le$"),
            '≥' => out.push_str("$\\ge$"),
            '∈' => out.push_str("$\\in$"),
            '−' => out.push_str("$-$"),
            'µ' => out.push_str("\\textmu{}"),
            '′' => out.push_str("$'$"),
            '⌈' => out.push_str("$\\lceil$"),
            '⌉' => out.push_str("$\\rceil$"),
            '²' => out.push_str("$^2$"),
            '→' => out.push_str("$\\to$"),
            _ => out.push(c),
        }
    }
    out
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
        assert_eq!(tex("τ_K"), "$\\tau$\\_K");
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
