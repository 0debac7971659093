//! Feather types a type map selects among: several kinds of feather in one
//! coat (scales on the legs, long coverts on the back), each a proportion
//! of its shape to the local spacing.

use super::FeatherShape;
use crate::error::{Error, ErrorKind, Result};

/// The most feather types one coat may have.
pub(crate) const MAX_FEATHER_TYPES: usize = 256;

/// One kind of feather: its length and width per local spacing and a
/// thickness multiplier. Zero proportions take the configuration's; every
/// type shares the configuration's shaft segments and bend limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeatherType {
    /// Shaft length over the local spacing (0: `Config::length_per_spacing`).
    pub length_per_spacing: f32,
    /// Vane width over the local spacing (0: `Config::width_per_spacing`).
    pub width_per_spacing: f32,
    /// Multiplier of the thickness the width gives (0: 1).
    pub thickness_scale: f32,
}

impl FeatherType {
    /// Checks the proportions: finite and ≥ 0, and within the range the
    /// configuration's own proportions allow.
    pub fn check(&self, index: usize) -> Result<()> {
        for (name, v) in [
            ("length_per_spacing", self.length_per_spacing),
            ("width_per_spacing", self.width_per_spacing),
            ("thickness_scale", self.thickness_scale),
        ] {
            if !v.is_finite() || !(0.0..=100.0).contains(&v) {
                let text = format!("feather type {index}: {name} is {v}; it must be finite, 0 to 100");
                return Err(Error::new(ErrorKind::InvalidArgument, text));
            }
        }
        Ok(())
    }

    /// The shape of a feather of this type at local spacing `d`, its zero
    /// proportions taken from `(length, width)` per spacing.
    pub fn shape(&self, d: f32, (length_per_spacing, width_per_spacing): (f32, f32)) -> FeatherShape {
        let or = |v: f32, fallback: f32| if v > 0.0 { v } else { fallback };
        let mut s = FeatherShape::proportioned(
            d,
            or(self.length_per_spacing, length_per_spacing),
            or(self.width_per_spacing, width_per_spacing),
        );
        s.thickness *= or(self.thickness_scale, 1.0);
        s
    }
}

/// A type map as the caller hands it in: a type index per vertex into a
/// table of types.
#[derive(Clone, Copy, Debug)]
pub struct FeatherTypeMap<'a> {
    /// Per vertex, an index into `types`.
    pub per_vertex: &'a [u32],
    /// The types (1 to 256).
    pub types: &'a [FeatherType],
}

impl FeatherTypeMap<'_> {
    /// Checks the table and the indices against `vertex_count`.
    pub fn check(&self, vertex_count: usize) -> Result<()> {
        let n = self.types.len();
        if n == 0 || n > MAX_FEATHER_TYPES {
            let text = format!("{n} feather types; there must be 1 to {MAX_FEATHER_TYPES}");
            return Err(Error::new(ErrorKind::InvalidArgument, text));
        }
        self.types.iter().enumerate().try_for_each(|(k, t)| t.check(k))?;
        if self.per_vertex.len() != vertex_count {
            let text = format!("feather_type holds {} values for {vertex_count} vertices", self.per_vertex.len());
            return Err(Error::new(ErrorKind::InvalidMesh, text));
        }
        if let Some(v) = self.per_vertex.iter().position(|&t| t as usize >= n) {
            let text = format!("vertex {v} has feather type {} of {n}", self.per_vertex[v]);
            return Err(Error::new(ErrorKind::IndexOutOfRange, text));
        }
        Ok(())
    }
}
