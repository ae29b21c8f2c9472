//! An environment's left-right mirror, for symmetry data augmentation
//! (rsl_rl's `symmetry_cfg`; Mittal et al. 2024, "Symmetry considerations
//! for learning task symmetric robot policies"): a robot whose body and
//! task are symmetric about its sagittal plane can learn from every sample
//! and from the sample's mirror image, which the simulator never ran.
//!
//! The environment says how its observation rows and action rows mirror;
//! the learner ([`crate::PpoConfig::mirror_augmentation`]) does the rest.

/// How an environment's rows mirror. Both maps are their own inverse.
pub trait Mirror: Send + Sync {
    /// Mirrors one observation row (privileged values included), raw
    /// (before normalisation), in place.
    fn mirror_observation(&self, row: &mut [f32]);
    /// Mirrors one action row, raw (the learner's sample before clipping),
    /// in place.
    fn mirror_action(&self, row: &mut [f32]);
}
