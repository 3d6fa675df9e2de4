//! The committed rows that may lack a file every run now writes: the PBCS rows written before
//! runs saved their evaluation episodes (`s<seed>.evaluation.csv`), listed in
//! `<results>/raw/legacy_without_evaluation.txt`. Every other row is checked against that file
//! ([`super::row`]): a row whose evaluation is missing is refused, so a row cannot claim a
//! success its files do not show.

use crate::error::{Error, Result};
use std::path::Path;

/// The list's file name, in a results folder's `raw/`.
pub const LEGACY_WITHOUT_EVALUATION: &str = "legacy_without_evaluation.txt";

/// Whether the row at `row` (`<results>/raw/<experiment>/<cell>/s<seed>.csv`) is one of the
/// listed rows that may lack its evaluation file. No list: none may.
pub(super) fn may_lack_evaluation(row: &Path) -> Result<bool> {
    let Some(raw) = row.ancestors().nth(3) else {
        return Ok(false);
    };
    let list = raw.join(LEGACY_WITHOUT_EVALUATION);
    let text = match std::fs::read_to_string(&list) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(false),
        Err(e) => return Err(Error::io(&list, e)),
    };
    let Ok(relative) = row.strip_prefix(raw) else {
        return Ok(false);
    };
    let relative = relative.to_string_lossy().replace('\\', "/");
    Ok(text
        .lines()
        .map(str::trim)
        .any(|l| !l.starts_with('#') && l == relative))
}
