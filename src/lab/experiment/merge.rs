//! The deep merge that resolves an experiment cell's job from its TOML tables.

/// Merges `from` into `into`: tables merge key by key, anything else replaces. A `learner.algo`
/// of another learner family than `into`'s (`sac` over `ddpg`) starts the learner table afresh:
/// one family's settings are not another's ([`crate::learner::LearnerConfig::switch_to`]).
pub(crate) fn merge(into: &mut toml::Table, from: &toml::Table) {
    let algo = |t: &toml::Table| {
        t.get("learner")
            .and_then(|l| l.get("algo"))
            .and_then(|a| a.as_str())
            .map(str::to_string)
    };
    if let Some(new) = algo(from) {
        let old = algo(into).unwrap_or_else(|| "ddpg".into());
        let family = |a: &str| crate::learner::LearnerConfig::preset(a).ok();
        if let (Some(a), Some(b)) = (family(&old), family(&new)) {
            if !a.same_family(&b) {
                into.remove("learner");
            }
        }
    }
    merge_tables(into, from);
}

fn merge_tables(into: &mut toml::Table, from: &toml::Table) {
    for (k, v) in from {
        match (into.get_mut(k), v) {
            (Some(toml::Value::Table(a)), toml::Value::Table(b)) => merge_tables(a, b),
            _ => {
                into.insert(k.clone(), v.clone());
            }
        }
    }
}

/// [`merge`] of a method's `set`, a `by_maze` or a profile's table (`what`: whose), refusing
/// the keys a grid sets itself: its sites say where each run is (`maze.size`; `env` is refused
/// where the job is placed, [`super::site::place`]) and its seeds which runs there are (`seed`),
/// so such a key would be silently replaced.
pub(crate) fn merge_over(
    into: &mut toml::Table,
    from: &toml::Table,
    what: &str,
) -> crate::error::Result<()> {
    let maze = from.get("maze").and_then(toml::Value::as_table);
    let grid_key = [
        from.contains_key("seed").then_some("seed"),
        maze.is_some_and(|m| m.contains_key("size"))
            .then_some("maze.size"),
    ];
    if let Some(key) = grid_key.into_iter().flatten().next() {
        return Err(crate::error::Error::invalid(
            key,
            format!(
                "{what} sets it, which the grid sets for each run (its `mazes` and `envs`, \
                 its seeds): list the site or the seeds in the experiment file instead"
            ),
        ));
    }
    merge(into, from);
    Ok(())
}

/// The base job of a method (`whose`, as the message says it: "method `a`"): the file `base`
/// names beside the experiment file (in `folder`), read as a table; a `base` that names no
/// file there is an error naming the field.
pub(crate) fn read_base(
    folder: &std::path::Path,
    base: &std::path::Path,
    whose: &str,
) -> crate::error::Result<toml::Table> {
    let path = folder.join(base);
    if base.as_os_str().is_empty() || !path.is_file() {
        return Err(crate::error::Error::invalid(
            "base",
            format!(
                "{whose}: {base:?} is not a file beside the experiment file (a job \
                 such as \"pbcs_paper.toml\" or \"baseline.toml\")"
            ),
        ));
    }
    crate::validate::read_toml(&path)
}

/// The tables that override a method's job at the site `key`, in order, each merged with
/// [`merge_over`]: the file's `by_maze` table for the site, the profile's table, the profile's
/// `by_maze` table for the site (each `None` where the file has none).
pub(crate) fn merge_site_layers(
    into: &mut toml::Table,
    key: &str,
    layers: [Option<&toml::Table>; 3],
) -> crate::error::Result<()> {
    let names = [
        format!("by_maze.{key}"),
        "the profile".to_string(),
        format!("the profile's by_maze.{key}"),
    ];
    for (layer, what) in layers.into_iter().zip(names) {
        if let Some(t) = layer {
            merge_over(into, t, &what)?;
        }
    }
    Ok(())
}
