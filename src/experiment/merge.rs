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
