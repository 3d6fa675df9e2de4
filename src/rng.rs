//! All randomness of a run, derived from one seed through named ChaCha streams.
//!
//! A run seed fixes a ChaCha8 key; each consumer (maze generation, exploration, weight
//! initialisation, ...) reads its own *stream* of that key, selected with
//! [`ChaCha8Rng::set_stream`]. Streams are independent, so adding draws to one consumer never
//! shifts the numbers another one sees, and every generator is passed explicitly: nothing in
//! the crate reads a global or thread-local RNG.
//!
//! ```
//! use pbcs::rng::{Seeds, Stream};
//! use rand::Rng;
//!
//! let mut a = Seeds::new(7).stream(Stream::Explore);
//! let mut b = Seeds::new(7).stream(Stream::Explore);
//! let mut c = Seeds::new(7).stream(Stream::Noise);
//! let (x, y, z): (u64, u64, u64) = (a.random(), b.random(), c.random());
//! assert_eq!(x, y); // same seed, same stream: same numbers
//! assert_ne!(x, z); // another stream of the same seed: other numbers
//! ```

use rand::SeedableRng;
pub use rand_chacha::ChaCha8Rng;

/// The generator used everywhere in the crate.
pub type Rng = ChaCha8Rng;

/// The named consumers of randomness. The discriminant is the stream number, so it is
/// part of the reproducibility contract: never renumber an existing variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Stream {
    /// Maze layout generation (seeded by the *maze* seed, not the run seed).
    Maze = 1,
    /// Phase 1: state selection tie-breaks and random actions.
    Explore = 2,
    /// Initial network weights.
    Init = 3,
    /// Exploration noise added to actions.
    Noise = 4,
    /// Replay-buffer sampling.
    Replay = 5,
    /// Start states of training and test episodes.
    Start = 6,
    /// Evaluation episodes.
    Eval = 7,
    /// Inside a learner update: TD3's target-smoothing noise, the argmax actor's samples.
    Update = 8,
    /// Starts of the chain's verification episodes (`phase2.chain_verify_episodes`).
    ChainVerify = 9,
    /// Goals of evaluation episodes drawn as the environment's reset draws them, for a chain
    /// whose last skill aims at each episode's own (`phase2.last_goal = "drawn"`).
    EvalGoal = 10,
}

/// A run seed, from which every stream of the run is derived.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Seeds {
    seed: u64,
}

impl Seeds {
    /// Seeds of the run with this seed.
    pub fn new(seed: u64) -> Self {
        Seeds { seed }
    }

    /// The generator of one consumer.
    pub fn stream(&self, stream: Stream) -> Rng {
        self.substream(stream, 0)
    }

    /// The seeds of sub-run `index` (phase 2 gives each skill a fresh learner whose weights
    /// and update noise come from its own seeds). Index 0 is the run itself.
    pub fn skill(&self, index: u32) -> Seeds {
        if index == 0 {
            return *self;
        }
        let mut rng = self.substream(Stream::Init, index);
        Seeds::new(rand::RngCore::next_u64(&mut rng))
    }

    /// The `index`-th generator of one consumer, for consumers that need many independent
    /// generators (one per skill, one per evaluation episode, ...).
    pub fn substream(&self, stream: Stream, index: u32) -> Rng {
        let mut rng = Rng::seed_from_u64(self.seed);
        rng.set_stream(((stream as u64) << 32) | u64::from(index));
        rng
    }
}
