//! Phase 2's settings checked against the environment they run on: a setting that needs a
//! hook the environment lacks is refused ([`Phase2Config::require_hooks`]), and what passes is
//! [`Ready`], what phase 2's entry points take.

use super::goal::BallMetric;
use super::procedure::{EpisodeLimit, Phase2Config};
use super::{FirstStarts, LastGoal, StartMode};
use crate::env::Env;
use crate::error::Result;
use crate::validate::Check;

impl Phase2Config {
    /// These settings checked ([`Check`]) and checked against `env`
    /// ([`Phase2Config::require_hooks`]): what phase 2's entry points take ([`Ready`]).
    pub fn ready<E: Env + ?Sized>(&self, env: &E) -> Result<Ready<'_, E>> {
        self.check()?;
        self.ready_checked(env)
    }

    /// [`Phase2Config::ready`] for settings already checked (a part of a
    /// [`crate::validate::Valid`] job): the hooks only.
    pub(crate) fn ready_checked<E: Env + ?Sized>(&self, env: &E) -> Result<Ready<'_, E>> {
        self.require_hooks(env)?;
        Ok(Ready {
            config: self,
            reach: env.step_reach(),
            env: std::marker::PhantomData,
        })
    }

    /// Refuses, naming the setting and the hook, a setting that needs a hook of [`Env`] that
    /// `env` does not offer: ball starts and the chain's verification need
    /// [`Env::ball_starts`], `stop_at_failure` and hand-over moves [`Env::clear_balls`],
    /// `shorten` [`Env::connector`], path limits [`Env::step_reach`], the last skill aiming at
    /// the success region [`Env::success_region`]. (Before, each silently did something else:
    /// exact starts, no stop, no shortening, the smallest action bound as a step's reach, τ_N
    /// as the target.)
    pub fn require_hooks<E: Env + ?Sized>(&self, env: &E) -> Result<()> {
        use crate::env::Capability;
        let i = &self.ideas;
        if let super::ChainStrategy::GoalConditioned(settings) = &self.chain {
            Capability::Goals.require(env, "phase2.chain = \"goal_conditioned\"")?;
            if settings.rest_starts {
                let setting = "phase2.goal_conditioned.rest_starts = true";
                Capability::RestStarts.require(env, setting)?;
            }
        }
        match self.start {
            StartMode::Ball => Capability::SampleBall.require(env, "phase2.start = \"ball\"")?,
            // Where no archived state lies in the ball, the environment's own sample.
            StartMode::Archive => {
                Capability::SampleBall.require(env, "phase2.start = \"archive\"")?
            }
            StartMode::Exact => {}
        }
        if self.ball != BallMetric::Position {
            Capability::VelocityBalls.require(env, "phase2.velocity_scale")?;
        }
        if i.chain_check.is_some() {
            Capability::SampleBall.require(env, "phase2.chain_verify_episodes")?;
        }
        if i.stop_at_failure {
            Capability::BallIsClear.require(env, "phase2.stop_at_failure")?;
        }
        if i.dead_walk.is_some_and(|d| d.retargets > 0) {
            // Moved hand-overs try clear balls first.
            Capability::BallIsClear.require(env, "phase2.retargets")?;
        }
        if i.shorten {
            Capability::Connect.require(env, "phase2.shorten")?;
        }
        if let Some(limit) = i.episode_limit {
            let setting = match limit {
                EpisodeLimit::Every(_) => "phase2.path_limit",
                EpisodeLimit::Greedy(_) => "phase2.test_path_limit",
            };
            Capability::StepReach.require(env, setting)?;
        }
        match self.last_goal {
            LastGoal::SuccessRegion => {
                Capability::SuccessRegion.require(env, "phase2.last_goal = \"success_region\"")?
            }
            LastGoal::Drawn => {
                Capability::DrawGoals.require(env, "phase2.last_goal = \"drawn\"")?
            }
            LastGoal::Ball => {}
        }
        if self.first_starts == FirstStarts::Drawn {
            Capability::DrawStarts.require(env, "phase2.first_starts = \"drawn\"")?;
        }
        Ok(())
    }
}

/// Phase 2's settings, checked and checked against the environment they run on: made once per
/// run by [`Phase2Config::ready`] (or by a run from its valid job), taken by
/// [`super::Phase2Inputs`] and [`super::SkillTask::new`], which check nothing again.
#[derive(Debug)]
pub struct Ready<'a, E: ?Sized> {
    config: &'a Phase2Config,
    /// The checked environment's [`Env::step_reach`]: present where the settings' path limits
    /// need it (checked), taken from the instance checked.
    reach: Option<f32>,
    env: std::marker::PhantomData<fn(&E)>,
}

impl<E: ?Sized> Clone for Ready<'_, E> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<E: ?Sized> Copy for Ready<'_, E> {}

impl<'a, E: ?Sized> Ready<'a, E> {
    /// The settings.
    pub fn settings(self) -> &'a Phase2Config {
        self.config
    }

    /// How far one step of the checked environment goes ([`Env::step_reach`]); `Some` whenever
    /// the settings have a path limit.
    pub fn step_reach(self) -> Option<f32> {
        self.reach
    }
}
