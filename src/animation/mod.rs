//! Animation (paper §3.3, DESIGN.md §5): what changed between two frames:
//! how roots moved relative to each other (`motion`), which feathers an
//! earlier feather now lies on (`contact`), and how much each feather's
//! pose changed (`coherence`). The frame update that uses them is
//! [`crate::frame`].

pub mod coherence;
pub mod contact;
pub mod motion;
