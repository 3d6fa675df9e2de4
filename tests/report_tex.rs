//! pdflatex can read every character of the report (`paper/report.tex` and the
//! `paper/generated/*.tex` it includes): its `utf8` input encoding defines few symbols beyond
//! Latin letters, and an undefined one (a `Φ` in a generated table) stops `make paper`. So the
//! report and the generated files are ASCII; `pbcs::report::tex` writes Greek letters and
//! symbols as math.

use std::path::Path;

/// Each character outside ASCII in `text`, with its line.
fn outside_ascii(text: &str) -> Vec<(usize, char)> {
    text.lines()
        .enumerate()
        .flat_map(|(i, line)| {
            line.chars()
                .filter(|c| !c.is_ascii())
                .map(move |c| (i + 1, c))
        })
        .collect()
}

#[test]
fn the_report_and_its_generated_files_are_ascii() {
    let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("paper");
    let mut files = vec![paper.join("report.tex")];
    let generated = std::fs::read_dir(paper.join("generated")).expect("paper/generated");
    files.extend(
        generated
            .map(|entry| entry.expect("an entry of paper/generated").path())
            .filter(|path| path.extension().is_some_and(|e| e == "tex")),
    );
    assert!(files.len() > 10, "the generated files are there: {files:?}");
    for file in files {
        let text = std::fs::read_to_string(&file).expect("a .tex file");
        let found = outside_ascii(&text);
        assert!(
            found.is_empty(),
            "{} holds characters pdflatex may not know (line, character): {found:?}; write them \
             as LaTeX (pbcs::report::tex)",
            file.display()
        );
    }
}

#[test]
fn the_check_finds_a_greek_letter_and_its_line() {
    assert_eq!(outside_ascii("a\nΦ(s) = 1\n$\\Phi$"), vec![(2, 'Φ')]);
    assert_eq!(pbcs::report::tex("Φ(s)"), "$\\Phi$(s)");
    assert!(outside_ascii(&pbcs::report::tex("σ of the noise, ±0.1")).is_empty());
}
