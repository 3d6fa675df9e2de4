//! Experiment files: parsing, validation and the deep merge that resolves each cell's job
//! (base file ← method `set` ← `by_maze` ← profile), and the declared figures and report.

use super::declared::{check_figures, check_report};
use super::merge::{merge_over, merge_site_layers, read_base};
use super::site::{paper_run, place};
use super::{
    check_seeds, Cell, CellKey, Experiment, ExperimentName, FigureSpec, Job, Kind, Method,
    ReportSpec, Site,
};
use crate::config::{PbcsJob, TrainJob};
use crate::envs::pointmaze::PointMazeConfig;
use crate::envs::EnvName;
use crate::error::{Error, Result};
use crate::validate::Check;
use serde::Deserialize;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// One method (a column of the results table, a bar of the γ study) as written in the file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MethodSpec {
    pub(super) name: String,
    #[serde(default)]
    label: Option<String>,
    kind: Kind,
    /// Base config, relative to the experiment file's folder.
    base: PathBuf,
    #[serde(default)]
    set: toml::Table,
    /// The paper's environment steps for this method, by maze size (as a string key).
    #[serde(default)]
    pub(super) paper_steps: BTreeMap<String, u64>,
    /// Whether the paper's run solved the maze, by maze size.
    #[serde(default)]
    pub(super) paper_solved: BTreeMap<String, bool>,
    /// The maze sizes this method runs, a subset of the experiment's (default: all of them):
    /// a grid whose rows ask different questions (the ablations) need not run every method
    /// on every size.
    #[serde(default)]
    mazes: Option<Vec<usize>>,
    /// The environments of the file's `envs` this method runs (default: all of them; `[]`
    /// for none, as a vanilla method must, the baselines running on the maze only).
    #[serde(default)]
    envs: Option<Vec<EnvName>>,
}

/// Fields set on every method of one kind: `vanilla = { … }` changes the [`TrainJob`]s,
/// `pbcs = { … }` the [`PbcsJob`]s.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct KindTables {
    #[serde(default)]
    vanilla: toml::Table,
    #[serde(default)]
    pbcs: toml::Table,
}

impl KindTables {
    /// The profile's table for `kind` (`vanilla = …` or `pbcs = …` in the profile).
    fn of_profile(prof: &ProfileSpec, kind: Kind) -> &toml::Table {
        match kind {
            Kind::Vanilla => &prof.vanilla,
            Kind::Pbcs => &prof.pbcs,
        }
    }

    fn of(&self, kind: Kind) -> &toml::Table {
        match kind {
            Kind::Vanilla => &self.vanilla,
            Kind::Pbcs => &self.pbcs,
        }
    }
}

/// A named profile: a smaller (`smoke`) or otherwise changed version of the same grid.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ProfileSpec {
    #[serde(default)]
    description: String,
    seeds: Option<u64>,
    mazes: Option<Vec<usize>>,
    /// The environments this profile runs, instead of the file's `envs`.
    envs: Option<Vec<EnvName>>,
    picture_seeds: Option<Vec<u64>>,
    #[serde(default)]
    vanilla: toml::Table,
    #[serde(default)]
    pbcs: toml::Table,
    /// Fields set on one maze size only (`[profile.<p>.by_maze."15"]`), after the rest.
    #[serde(default)]
    by_maze: BTreeMap<String, KindTables>,
    /// Methods this profile adds after the file's own (`[[profile.<p>.method]]`).
    #[serde(default, rename = "method")]
    methods: Vec<MethodSpec>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ExperimentSpec {
    title: String,
    #[serde(default)]
    description: String,
    seeds: u64,
    /// Fewer seeds on some sizes or environments (`seeds_by_maze = { "32" = 3 }`), at most
    /// `seeds`.
    #[serde(default)]
    seeds_by_maze: BTreeMap<String, u64>,
    #[serde(default)]
    first_seed: u64,
    #[serde(default = "default_picture_seeds")]
    picture_seeds: Vec<u64>,
    /// Maze sizes, the grid's first rows.
    #[serde(default)]
    mazes: Vec<usize>,
    /// Other environments of the registry (`envs = ["rooms"]`), the rows after the mazes:
    /// every PBCS method runs on each, its job's `env` set to it.
    #[serde(default)]
    envs: Vec<EnvName>,
    /// The map of the sites `pointmaze` and `antmaze` (a map of one's own), as a job's
    /// `[pointmaze]` writes it; a `map_file` is read relative to this file's folder.
    #[serde(default)]
    pointmaze: Option<toml::Table>,
    #[serde(rename = "method")]
    pub(super) methods: Vec<MethodSpec>,
    /// Fields set on one maze size or environment only (`[by_maze."15"]`, e.g. a budget per
    /// size; `[by_maze.rooms]`), applied after the methods' own tables and before the
    /// profile's.
    #[serde(default)]
    by_maze: BTreeMap<String, KindTables>,
    #[serde(default, rename = "profile")]
    profiles: BTreeMap<String, ProfileSpec>,
    #[serde(default, rename = "figure")]
    figures: Vec<FigureSpec>,
    #[serde(default)]
    report: ReportSpec,
    /// A pre-registered grid: the preset it runs and that file's hash when registered.
    #[serde(default)]
    registered: Option<super::Registration>,
    /// A grid whose rows are committed as its runs finish (runs of hours each): its tables
    /// hold the cells and seeds with rows so far.
    #[serde(default)]
    in_progress: bool,
}

pub(crate) fn default_picture_seeds() -> Vec<u64> {
    vec![0]
}

/// A validation error with where it happened (`where_`) added to its reason.
pub(crate) fn located(e: Error, where_: &str) -> Error {
    match e {
        Error::Invalid { field, reason } => Error::Invalid {
            field,
            reason: format!("{reason} ({where_})"),
        },
        other => other,
    }
}

/// Sites of a grid: at least one, each once, the maze written by its sizes (`mazes`), never
/// as `envs = ["maze"]`.
pub(crate) fn check_sites(sites: &[Site]) -> Result<()> {
    if sites.contains(&Site::Env(EnvName::Maze)) {
        return Err(Error::invalid(
            "envs",
            "`maze` is not one of `envs`: list its sizes in `mazes`",
        ));
    }
    if sites.is_empty() {
        return Err(Error::invalid(
            "mazes",
            "must name at least one maze size (or an environment in `envs`)",
        ));
    }
    if sites.iter().collect::<BTreeSet<_>>().len() != sites.len() {
        return Err(Error::invalid(
            "mazes",
            "maze sizes and environments must be unique",
        ));
    }
    Ok(())
}

/// A key of `seeds_by_maze`, `by_maze` or `paper_steps` read as one of `sites` (its size or
/// name), or None.
fn site_key(key: &str, sites: &[Site]) -> Option<Site> {
    key.parse::<Site>().ok().filter(|s| sites.contains(s))
}

/// A method's name and its label in tables and figures.
type MethodLabel = (Method, String);

impl ExperimentSpec {
    /// The profile named `profile` of the file at `path` (None: the committed grid, an empty
    /// profile).
    fn profile(&self, path: &Path, profile: Option<&str>) -> Result<ProfileSpec> {
        match profile {
            None => Ok(ProfileSpec::default()),
            Some(p) => self.profiles.get(p).cloned().ok_or_else(|| {
                Error::invalid(
                    "profile",
                    format!(
                        "{} has no profile `{p}` (it has: {})",
                        path.display(),
                        self.profiles.keys().cloned().collect::<Vec<_>>().join(", ")
                    ),
                )
            }),
        }
    }

    /// The file's own sites: its maze sizes, then its environments.
    fn sites(&self) -> Vec<Site> {
        let mazes = self.mazes.iter().map(|&n| Site::Maze(n));
        mazes
            .chain(self.envs.iter().map(|&e| Site::Env(e)))
            .collect()
    }

    /// `seeds_by_maze`, its keys read as sites of the file, each count 1 to `seeds`.
    fn seeds_by_maze(&self) -> Result<BTreeMap<Site, u64>> {
        let sites = self.sites();
        let mut out = BTreeMap::new();
        for (key, &n) in &self.seeds_by_maze {
            match site_key(key, &sites) {
                Some(site) if (1..=self.seeds).contains(&n) => {
                    out.insert(site, n);
                }
                _ => {
                    return Err(Error::invalid(
                        "seeds_by_maze",
                        format!(
                            "\"{key}\" = {n}: needs a maze size or environment of the file \
                             ({}) and 1 to `seeds` ({}) seeds",
                            fmt_sites(&sites),
                            self.seeds
                        ),
                    ))
                }
            }
        }
        Ok(out)
    }

    /// The file's `by_maze` may name any site the file or one of its profiles runs (a profile
    /// narrows the sizes); the profile's `prof`, only the sites it runs (`sites`).
    fn check_by_maze(&self, path: &Path, prof: &ProfileSpec, sites: &[Site]) -> Result<()> {
        let mut file_sites: BTreeSet<Site> = self.sites().into_iter().collect();
        for p in self.profiles.values() {
            file_sites.extend(p.mazes.iter().flatten().map(|&n| Site::Maze(n)));
        }
        let file_sites: Vec<Site> = file_sites.into_iter().collect();
        for (field, by_maze, sites) in [
            ("by_maze", &self.by_maze, file_sites.as_slice()),
            ("profile.by_maze", &prof.by_maze, sites),
        ] {
            for key in by_maze.keys() {
                if site_key(key, sites).is_none() {
                    return Err(Error::invalid(
                        format!("{field} in {}", path.display()),
                        format!(
                            "`{key}` is not one of the maze sizes or environments ({})",
                            fmt_sites(sites)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Each method's name is valid and unique, its own `mazes` a non-empty subset of the
    /// file's and its own `envs` a subset, its paper numbers keyed by sites of the file.
    fn check_methods(&self, all_methods: &[&MethodSpec]) -> Result<()> {
        let mut names = BTreeSet::new();
        for m in all_methods.iter().copied() {
            Method::new(&m.name)?;
            if !names.insert(m.name.clone()) {
                return Err(Error::invalid(
                    "method.name",
                    format!("`{}` appears twice", m.name),
                ));
            }
            if let Some(own) = &m.mazes {
                if own.is_empty() || own.iter().any(|n| !self.mazes.contains(n)) {
                    return Err(Error::invalid(
                        "method.mazes",
                        format!(
                            "method `{}`: {own:?} must be a non-empty subset of `mazes` {:?}",
                            m.name, self.mazes
                        ),
                    ));
                }
            }
            if let Some(own) = &m.envs {
                if own.iter().any(|e| !self.envs.contains(e)) {
                    return Err(Error::invalid(
                        "method.envs",
                        format!("method `{}`: {own:?} must be a subset of `envs`", m.name),
                    ));
                }
            }
            for key in m.paper_steps.keys().chain(m.paper_solved.keys()) {
                if site_key(key, &self.sites()).is_none() {
                    return Err(Error::invalid(
                        "method.paper_steps",
                        format!(
                            "method `{}`: `{key}` is not one of the maze sizes or environments",
                            m.name
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The map of the sites `pointmaze` and `antmaze` (`[pointmaze]`, its `map_file` relative to
    /// the file's folder), checked; required exactly when `sites` has one of them.
    fn own_map(&self, path: &Path, sites: &[Site]) -> Result<Option<PointMazeConfig>> {
        let takes_map = |s: &Site| matches!(s, Site::Env(e) if e.takes_map());
        let has_site = sites.iter().any(takes_map);
        let Some(table) = &self.pointmaze else {
            return match has_site {
                true => Err(Error::invalid(
                    "pointmaze",
                    "the sites `pointmaze` and `antmaze` run a map of one's own: give it in the \
                     file's [pointmaze] (`map = [\"111\", ...]` or `map_file = \"maps/x.txt\"`)",
                )),
                false => Ok(None),
            };
        };
        if !self.sites().iter().any(takes_map) {
            return Err(Error::invalid(
                "pointmaze",
                "gives a map, but neither `pointmaze` nor `antmaze` is one of the file's `envs` \
                 (add one)",
            ));
        }
        let mut table = table.clone();
        if let Some(toml::Value::String(file)) = table.get("map_file") {
            let folder = path.parent().unwrap_or(Path::new("."));
            let file = folder.join(file).to_string_lossy().into_owned();
            table.insert("map_file".into(), toml::Value::String(file));
        }
        let map: PointMazeConfig = toml::Value::Table(table)
            .try_into()
            .map_err(|e| Error::parse(path, format!("[pointmaze]: {e}")))?;
        map.check()?;
        Ok(Some(map))
    }

    /// The methods (name, label) and the cells of the grid: each method's base file with its
    /// `set` merged once, then per maze size the file's `by_maze`, the profile's tables and
    /// the profile's `by_maze`, resolved into a validated job.
    fn cells(
        &self,
        path: &Path,
        prof: &ProfileSpec,
        all_methods: &[&MethodSpec],
        sites: &[Site],
    ) -> Result<(Vec<MethodLabel>, Vec<Cell>)> {
        let folder = path.parent().unwrap_or(Path::new("."));
        let mut methods = Vec::new();
        let mut resolved = Vec::new();
        for m in all_methods.iter().copied() {
            let whose = format!("method `{}`", m.name);
            let mut table = read_base(folder, &m.base, &whose)?;
            merge_over(&mut table, &m.set, &whose)?;
            let label = m.label.clone().unwrap_or_else(|| m.name.clone());
            methods.push((Method::new(&m.name)?, label.clone()));
            resolved.push((m, label, table));
        }
        let own_map = self.own_map(path, sites)?;
        let mut cells = Vec::new();
        for &site in sites {
            let key = site.to_string();
            for (m, label, table) in &resolved {
                let runs_here = match site {
                    Site::Maze(n) => m.mazes.as_ref().is_none_or(|own| own.contains(&n)),
                    Site::Env(e) => m.envs.as_ref().is_none_or(|own| own.contains(&e)),
                };
                if !runs_here {
                    continue;
                }
                let mut table = table.clone();
                let layers = [
                    self.by_maze.get(&key).map(|t| t.of(m.kind)),
                    Some(KindTables::of_profile(prof, m.kind)),
                    prof.by_maze.get(&key).map(|t| t.of(m.kind)),
                ];
                merge_site_layers(&mut table, &key, layers)?;
                let method = Method::new(&m.name)?;
                cells.push(Cell {
                    id: CellKey::new(method, site),
                    method,
                    label: label.clone(),
                    site,
                    job: cell_job(path, m, table, site, own_map.as_ref())?,
                    paper_steps: m.paper_steps.get(&key).copied(),
                    paper_solved: m.paper_solved.get(&key).copied(),
                });
            }
        }
        Ok((methods, cells))
    }
}

/// The validated job of method `m` on `site` from its merged `table` (seed 0).
fn cell_job(
    path: &Path,
    m: &MethodSpec,
    table: toml::Table,
    site: Site,
    own_map: Option<&PointMazeConfig>,
) -> Result<Job> {
    let where_ = format!("method `{}`, {}", m.name, site.title());
    let what = |e: toml::de::Error| {
        Error::parse(
            path,
            format!(
                "method `{}` ({} job, {}): {e}",
                m.name,
                m.kind.name(),
                site.title()
            ),
        )
    };
    let method = format!("method `{}`", m.name);
    let job = match m.kind {
        Kind::Vanilla => {
            let mut j: TrainJob = toml::Value::Table(table).try_into().map_err(what)?;
            place(&mut j, site, &method, own_map)?;
            Job::Vanilla(j)
        }
        Kind::Pbcs => {
            let mut j: PbcsJob = toml::Value::Table(table).try_into().map_err(what)?;
            place(&mut j, site, &method, own_map)?;
            Job::Pbcs(j)
        }
    };
    job.check().map_err(|e| located(e, &where_))?;
    Ok(job)
}

/// Sites as a file writes them: `2, 5, rooms`.
fn fmt_sites(sites: &[Site]) -> String {
    let names: Vec<String> = sites.iter().map(Site::to_string).collect();
    names.join(", ")
}

impl Experiment {
    /// Reads and resolves an experiment file under `profile` (None: the committed grid).
    /// Every cell's job is validated; duplicate method names, an unknown profile, an empty
    /// grid and keys that a job does not have are errors naming the method or field. Under a
    /// profile the whole grid is validated too, so that the smoke check CI runs holds the
    /// committed grid to the same checks.
    pub fn load(path: &Path, profile: Option<&str>) -> Result<Experiment> {
        if profile.is_some() {
            Experiment::load(path, None)?;
        }
        Experiment::resolve(path, profile).map_err(|e| e.in_file(path))
    }

    /// [`Experiment::load`]'s work, its errors not yet naming the file.
    fn resolve(path: &Path, profile: Option<&str>) -> Result<Experiment> {
        let spec: ExperimentSpec = crate::validate::read_toml(path)?;
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .ok_or_else(|| Error::parse(path, "no file name"))?;
        let name = ExperimentName::new(&stem).map_err(|e| Error::parse(path, e.to_string()))?;
        let prof = spec.profile(path, profile)?;
        check_seeds("seeds", spec.first_seed, spec.seeds, &spec.picture_seeds)?;
        let seed_count = prof.seeds.unwrap_or(spec.seeds);
        let picture_seeds = (prof.picture_seeds.clone()).unwrap_or(spec.picture_seeds.clone());
        let field = match profile {
            Some(p) => format!("profile.{p}.seeds"),
            None => "seeds".to_string(),
        };
        // The pictures the profile draws, its own or the file's it inherits: each among the
        // profile's seeds, or it would never be drawn.
        check_seeds(&field, spec.first_seed, seed_count, &picture_seeds)?;
        let mazes = prof.mazes.clone().unwrap_or(spec.mazes.clone());
        let envs = prof.envs.clone().unwrap_or(spec.envs.clone());
        let sites: Vec<Site> = (mazes.iter().map(|&n| Site::Maze(n)))
            .chain(envs.iter().map(|&e| Site::Env(e)))
            .collect();
        check_sites(&sites)?;
        let seeds_by_maze = spec.seeds_by_maze()?;
        let all_methods: Vec<&MethodSpec> = spec.methods.iter().chain(&prof.methods).collect();
        if all_methods.is_empty() {
            return Err(Error::invalid("method", "an experiment needs a [[method]]"));
        }
        spec.check_by_maze(path, &prof, &sites)?;
        spec.check_methods(&all_methods)?;
        let (methods, cells) = spec.cells(path, &prof, &all_methods, &sites)?;
        check_figures(path, &spec.figures, &methods)?;
        super::declared::check_paired(path, spec.registered.as_ref(), &methods)?;
        let bases: Vec<(&str, Kind, &Path)> = (all_methods.iter())
            .map(|m| (m.name.as_str(), m.kind, m.base.as_path()))
            .collect();
        super::declared::check_registered_base(path, spec.registered.as_ref(), &bases)?;
        check_report(path, &spec.report, &cells)?;
        Ok(Experiment {
            title: spec.title,
            description: if prof.description.is_empty() {
                spec.description
            } else {
                format!("{} ({})", spec.description, prof.description)
            },
            profile: profile.map(String::from),
            first_seed: spec.first_seed,
            seed_count,
            seeds_by_maze,
            picture_seeds,
            in_progress: spec.in_progress,
            registered: spec.registered.map(|r| super::Registration {
                preset_path: path.parent().unwrap_or(Path::new(".")).join(&r.preset),
                ..r
            }),
            report: spec.report,
            figures: if spec.figures.is_empty() {
                vec![FigureSpec::Bars {
                    name: name.to_string(),
                    baselines: Vec::new(),
                }]
            } else {
                spec.figures
            },
            name,
            sites,
            methods,
            cells,
        })
    }

    /// An experiment of one PBCS method `name` (letters, digits, `_`) run as `job` on each of
    /// `sizes` with seeds `0..seeds`, built from a job instead of a file: what `pbcs table`
    /// sweeps (into `<results>/raw/<name>/<name>-maze<N>/`, in the order of `sizes`). Each
    /// cell carries the paper's run of the same variant (with or without chaining) on its size
    /// ([`paper_run`]); seed 0 keeps its picture.
    ///
    /// ```
    /// use pbcs::experiment::Experiment;
    /// let exp = Experiment::of_job("mine", &pbcs::config::PbcsJob::default(), &[2, 5], 3).unwrap();
    /// assert_eq!(exp.cells[1].id, "mine-maze5".parse().unwrap());
    /// assert_eq!(exp.seeds(), vec![0, 1, 2]);
    /// assert!(Experiment::of_job("mine", &Default::default(), &[2, 2], 3).is_err());
    /// ```
    pub fn of_job(name: &str, job: &PbcsJob, sizes: &[usize], seeds: u64) -> Result<Experiment> {
        let method = Method::new(name)?;
        let sites: Vec<Site> = sizes.iter().map(|&n| Site::Maze(n)).collect();
        check_sites(&sites)?;
        check_seeds("--seeds", 0, seeds, &default_picture_seeds())?;
        let cells = sites
            .iter()
            .map(|&site| {
                let mut j = job.clone();
                place(&mut j, site, &format!("method `{name}`"), None)?;
                j.check().map_err(|e| located(e, &site.title()))?;
                let (paper_steps, paper_solved) = paper_run(job.phase2.variant(), site);
                Ok(Cell {
                    id: CellKey::new(method, site),
                    method,
                    label: name.to_string(),
                    site,
                    job: Job::Pbcs(j),
                    paper_steps,
                    paper_solved,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Experiment {
            name: ExperimentName::new(name)?,
            title: format!("PBCS ({name}) on mazes {sizes:?}"),
            description: String::new(),
            profile: None,
            first_seed: 0,
            seed_count: seeds,
            seeds_by_maze: BTreeMap::new(),
            picture_seeds: default_picture_seeds(),
            registered: None,
            in_progress: false,
            sites,
            methods: vec![(method, name.to_string())],
            cells,
            figures: vec![FigureSpec::Bars {
                name: name.to_string(),
                baselines: Vec::new(),
            }],
            report: ReportSpec::default(),
        })
    }
}
