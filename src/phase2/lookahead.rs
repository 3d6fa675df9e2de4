//! The hand-over lookahead (`phase2.lookahead`, ours: [`super::Ideas::lookahead`]). A skill's
//! goal ball B_ε(τ_T) counts as reached only where the next `n` skills already found, run
//! greedily from the state that entered it (each allowed `max_steps` actions to hand over, as
//! the chain's verification allows them), carry it to the n-th one's target; an entry from
//! which they do not ends the episode as a failure, paid the shaped reward without
//! [`super::goal::REACHED_REWARD`]. In training, tests, verification and a hand-over's tries
//! alike; the lookahead's steps are counted with the episode's. Skills verified from their own
//! balls need not work from where the chain hands them over (a jointed body's legs, issue 49:
//! `docs/antmaze.md`). The skills looked ahead to are those of the same section (a chain
//! repair's section sees only its own).

use super::goal::Goal;
use super::inputs::Along;
use super::SkillChain;
use crate::env::Env;
use crate::policy::Policy;

/// A hand-over lookahead ([`super::Ideas::lookahead`]): the next skills already found, in
/// execution order (the first one's ball is the task's goal), and the target they must carry
/// an entry to.
#[derive(Debug, Clone)]
pub struct Lookahead {
    /// The next skills, the first one's activation ball B_ε(τ_T). They act from the entry
    /// on, at least once, as a chain does ([`super::SkillChain::active_skill`]: a later one
    /// of them whose ball holds the state takes over).
    pub chain: SkillChain,
    /// The last of them's goal.
    pub target: Goal,
    /// Actions each of them may take to hand over (`max_steps`).
    pub per_skill: usize,
}

impl Lookahead {
    /// Whether the next skills, run greedily from `entry`, carry it to the target; and the
    /// environment steps they took.
    pub fn carries<E: Env>(&self, env: &E, entry: E::State) -> (bool, u64) {
        let limit = self.per_skill * self.chain.skills.len();
        let r = self
            .chain
            .run_until(env, entry, limit, Some(self.per_skill), Some(&self.target));
        (r.success, r.skill_used.len() as u64)
    }
}

impl Lookahead {
    /// The next `n` skills after a learning problem whose goal is τ_{lo+t} on the section from
    /// τ_lo, in execution order: of the skills `found` so far on it (Algorithm 1's order), the
    /// one whose start is τ_{lo+t}, and those found before it (a hand-over's try, whose goal is
    /// the target of the skill found last, looks ahead from the skill after it); and their
    /// target (`phase2.lookahead`). `None` when no skill found starts there (the first problem,
    /// and the first skill's hand-over tries).
    pub(super) fn after<E: Env>(
        along: Along<'_, '_, E>,
        found: &[(usize, usize, Box<dyn Policy>)],
        lo: usize,
        t: usize,
        n: usize,
    ) -> Option<Lookahead> {
        let next = next_skills(found, t, n)?;
        let target = along.goal(lo + next.last()?.1);
        let chain = SkillChain {
            skills: along.skills(lo, next),
            kernel: along.inputs.kernel,
        };
        let per_skill = along.config().max_steps;
        Some(Lookahead {
            chain,
            target,
            per_skill,
        })
    }
}

/// Of the skills `found` (Algorithm 1's order, decreasing K), the one that starts at τ_t and
/// the `n` − 1 found before it, in execution order ([`Lookahead::after`]).
fn next_skills<P: Clone>(
    found: &[(usize, usize, P)],
    t: usize,
    n: usize,
) -> Option<Vec<(usize, usize, P)>> {
    let at = found.iter().rposition(|(k, _, _)| *k == t)?;
    Some(found[..=at].iter().rev().take(n).cloned().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `phase2.lookahead`'s skills: from a problem's goal τ_t, the skill found that starts there and
    /// those found before it, in execution order. A hand-over's try aims at the target of the skill
    /// found last, so it looks ahead from the skill after that one, never from itself.
    #[test]
    fn a_lookahead_starts_at_the_skill_that_starts_at_the_goal() {
        // Found backwards from τ_40: 30 → 40, then 20 → 30, then 10 → 20.
        let found = [(30, 40, "a"), (20, 30, "b"), (10, 20, "c")];
        let names =
            |t, n| next_skills(&found, t, n).map(|v| v.iter().map(|s| s.2).collect::<Vec<_>>());
        // The next problem aims at τ_10, where the skill found last starts.
        assert_eq!(names(10, 1), Some(vec!["c"]));
        assert_eq!(names(10, 2), Some(vec!["c", "b"]));
        assert_eq!(names(10, 100), Some(vec!["c", "b", "a"]));
        // A try to move the last skill's hand-over aims at its target τ_20.
        assert_eq!(names(20, 1), Some(vec!["b"]));
        assert_eq!(names(20, 2), Some(vec!["b", "a"]));
        // Nothing starts at τ_40 (the first skill's hand-over tries) or before any skill is found.
        assert_eq!(names(40, 1), None);
        assert_eq!(next_skills::<&str>(&[], 40, 1), None);
    }
}
