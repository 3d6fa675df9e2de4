//! The lab: what reproduces the paper on top of the core (the rest of the crate), and what the
//! core never imports (tests/layout.rs). A job's grid becomes runs ([`experiment`]: the
//! sweeps, their raw rows, [`launch`]: their commands and SLURM arrays), rows become tables
//! ([`tables`], [`aggregate`] with polars, [`criteria`]), tables become claims ([`claims`]),
//! figures ([`figures`], [`plot`] with plotters) and the report's LaTeX ([`report`],
//! [`mathtext`]); [`pipeline`] runs those steps, [`reproduce`] re-runs a table's cell.

#[cfg(feature = "polars")]
pub mod aggregate;
pub mod claims;
pub mod criteria;
pub mod experiment;
pub mod figures;
pub mod launch;
pub mod mathtext;
pub mod pipeline;
pub mod plot;
pub mod report;
pub mod reproduce;
pub mod tables;
