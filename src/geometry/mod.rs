//! Poses, rotation conventions and rigid fits.

mod conventions;
pub mod rigid_fit;

pub use conventions::*;
