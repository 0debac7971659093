//! Who lies on whom: growth priority and the feather order (paper §2.1–2.2,
//! §3.2–3.3; DESIGN §4, §5).
//!
//! * [`Neighbourhoods`]: k-nearest roots, the symmetric pair set and obstacle
//!   candidates at the current pose.

mod kd_tree;
mod neighbours;

pub use neighbours::{NeighbourParams, Neighbourhoods};
