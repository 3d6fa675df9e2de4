//! Stand-ins for the environments of a feature this build lacks.

/// Declares `$name`, an environment without values, for a build without the feature that
/// makes it: the registry refuses its names ([`EnvSpec::build`]), and code generic over the
/// registry's environments ([`crate::with_env!`]) still compiles.
#[cfg_attr(feature = "mujoco", allow(unused_macros))]
macro_rules! uninhabited_env {
    ($name:ident, $what:literal) => {
        #[doc = concat!("Without MuJoCo, ", $what, " has no values.")]
        #[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
        pub enum $name {}

        impl crate::env::Env for $name {
            type State = $name;
            fn obs_dim(&self) -> usize {
                match *self {}
            }
            fn action_dim(&self) -> usize {
                match *self {}
            }
            fn action_bound(&self, _: usize) -> f32 {
                match *self {}
            }
            fn start(&self) -> Self::State {
                match *self {}
            }
            fn sample_start(&self, _: &mut crate::rng::Rng) -> Self::State {
                match *self {}
            }
            fn observe(&self, _: &Self::State, _: &mut [f32]) {
                match *self {}
            }
            fn step(&self, _: &Self::State, _: &[f32]) -> crate::env::Step<Self::State> {
                match *self {}
            }
        }

        impl crate::env::Planar for $name {
            fn point(&self, _: &Self::State) -> (f32, f32) {
                match *self {}
            }
            fn scene(&self) -> crate::env::Scene {
                match *self {}
            }
            fn ball_point(&self, _: &[f32]) -> (f32, f32) {
                match *self {}
            }
        }
    };
}
#[cfg_attr(feature = "mujoco", allow(unused_imports))]
pub(crate) use uninhabited_env;
