//! Seeds and generator positions: how a run's seed becomes each iteration's
//! environment seed, and the state of a sampling generator that a
//! checkpoint stores so that a resumed run draws what the uninterrupted one
//! would have.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A well-mixed 64-bit value of `(seed, k)` (SplitMix64 finaliser).
pub fn derive_seed(seed: u64, k: u64) -> u64 {
    let mut z = seed ^ k.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A ChaCha8 generator's position, as a checkpoint stores it.
#[derive(Debug, Clone, PartialEq)]
pub struct RngState {
    /// the ChaCha8 seed
    pub seed: [u8; 32],
    /// its stream
    pub stream: u64,
    /// its word position
    pub word_pos: u128,
}

impl RngState {
    /// Where `rng` stands.
    pub fn of(rng: &ChaCha8Rng) -> Self {
        Self {
            seed: rng.get_seed(),
            stream: rng.get_stream(),
            word_pos: rng.get_word_pos(),
        }
    }

    /// A generator standing here.
    pub fn generator(&self) -> ChaCha8Rng {
        let mut rng = ChaCha8Rng::from_seed(self.seed);
        rng.set_stream(self.stream);
        rng.set_word_pos(self.word_pos);
        rng
    }
}

#[cfg(test)]
mod tests {
    use rand::Rng;

    use super::*;

    #[test]
    fn derived_seeds_differ_and_repeat() {
        assert_eq!(derive_seed(7, 3), derive_seed(7, 3));
        assert_ne!(derive_seed(7, 3), derive_seed(7, 4));
        assert_ne!(derive_seed(7, 3), derive_seed(8, 3));
    }

    #[test]
    fn a_generator_rebuilt_from_its_state_draws_the_same_values() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let _: u64 = rng.random();
        let mut copy = RngState::of(&rng).generator();
        let a: [u64; 4] = rng.random();
        let b: [u64; 4] = copy.random();
        assert_eq!(a, b);
    }
}
