//! Fixed and goal-conditioned tasks of the named maps: which names draw their goal per episode
//! (gymnasium-robotics' resets, `_goals`), and each one's counterpart.

use super::EnvName;
use crate::error::{Error, Result};

impl EnvName {
    /// Whether episodes draw their start and goal as gymnasium-robotics' reset does (the
    /// `_goals` names): a goal-conditioned task.
    ///
    /// ```
    /// use pbcs::envs::EnvName;
    /// assert!(EnvName::PointmazeUmazeGoals.goal_resets());
    /// assert!(!EnvName::PointmazeUmaze.goal_resets());
    /// assert_eq!(EnvName::PointmazeLargeGoals.point_map(), EnvName::PointmazeLarge.point_map());
    /// ```
    pub fn goal_resets(self) -> bool {
        matches!(
            self,
            EnvName::PointmazeUmazeGoals
                | EnvName::PointmazeOpenGoals
                | EnvName::PointmazeMediumGoals
                | EnvName::PointmazeLargeGoals
                | EnvName::AntmazeUmazeGoals
                | EnvName::AntmazeOpenGoals
                | EnvName::AntmazeMediumGoals
                | EnvName::AntmazeLargeGoals
        )
    }

    /// Refuses a run that needs one fixed task on an environment whose episodes draw their
    /// goal ([`EnvName::goal_resets`]): PBCS, and a vanilla run without HER (its networks
    /// would not see the goal). `what` names the run.
    pub fn check_fixed_task(self, what: &str) -> Result<()> {
        if self.goal_resets() {
            let fixed = format!(", or run {} for the fixed task", self.fixed_name());
            return Err(Error::invalid(
                "env",
                format!(
                    "{} draws each episode's goal (gymnasium-robotics' resets): {what} needs \
                     one fixed goal; train on it with [train.her] (the networks then see the \
                     goal){fixed}",
                    self.name(),
                ),
            ));
        }
        Ok(())
    }

    /// The name of the same map's fixed task, for a `_goals` name (itself for any other).
    pub fn fixed_name(self) -> &'static str {
        self.name().trim_end_matches("_goals")
    }

    /// The same map's fixed task, for a `_goals` name (itself for any other).
    ///
    /// ```
    /// use pbcs::envs::EnvName;
    /// assert_eq!(EnvName::PointmazeUmazeGoals.fixed_task(), EnvName::PointmazeUmaze);
    /// assert_eq!(EnvName::AntmazeLarge.fixed_task(), EnvName::AntmazeLarge);
    /// assert_eq!(EnvName::PointmazeUmaze.goals_task(), Some(EnvName::PointmazeUmazeGoals));
    /// assert_eq!(EnvName::Rooms.goals_task(), None);
    /// ```
    pub fn fixed_task(self) -> EnvName {
        let fixed = self.fixed_name();
        EnvName::all()
            .iter()
            .copied()
            .find(|e| e.name() == fixed)
            .unwrap_or(self)
    }

    /// The same map's goal-conditioned task (`_goals`), for a fixed task that has one.
    pub fn goals_task(self) -> Option<EnvName> {
        EnvName::all()
            .iter()
            .copied()
            .find(|e| e.goal_resets() && e.fixed_task() == self && *e != self)
    }
}
