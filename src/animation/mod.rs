//! Animation (paper §3.3, DESIGN.md §5): what changed between two frames.

pub mod coherence;
pub mod contact;
pub mod motion;
pub mod step;
