//! How a [`Config`](crate::Config) field is carried in `PlumageConfig`: the
//! `by` column of `crate::config::config_fields!` names one of these
//! carriers (or `SamplerCode` or `ModeCode`, beside their constants in
//! `ffi/config.rs`). `to_c` gives the C field(s) as a tuple; `from_c`
//! takes them back, refusing a value no Rust one has.

use super::convention::Failure;
use glam::Vec3;

/// The same type on both sides.
pub(crate) struct Same;

impl Same {
    pub(crate) fn to_c<T: Copy>(v: &T) -> (T,) {
        (*v,)
    }

    pub(crate) fn from_c<T>((v,): (T,)) -> Result<T, Failure> {
        Ok(v)
    }
}

/// A count as `uint32_t` (the ranges `validate` allows fit).
pub(crate) struct Narrow;

impl Narrow {
    pub(crate) fn to_c(v: &usize) -> (u32,) {
        (*v as u32,)
    }

    pub(crate) fn from_c((v,): (u32,)) -> Result<usize, Failure> {
        Ok(v as usize)
    }
}

/// A byte count as `uint64_t` (saturating where `usize` is narrower).
pub(crate) struct Bytes;

impl Bytes {
    pub(crate) fn to_c(v: &usize) -> (u64,) {
        (*v as u64,)
    }

    pub(crate) fn from_c((v,): (u64,)) -> Result<usize, Failure> {
        Ok(usize::try_from(v).unwrap_or(usize::MAX))
    }
}

/// A boolean as `uint32_t`, non-zero for true.
pub(crate) struct Flag;

impl Flag {
    pub(crate) fn to_c(v: &bool) -> (u32,) {
        (u32::from(*v),)
    }

    pub(crate) fn from_c((v,): (u32,)) -> Result<bool, Failure> {
        Ok(v != 0)
    }
}

/// A vector as `float[3]`.
pub(crate) struct Triple;

impl Triple {
    pub(crate) fn to_c(v: &Vec3) -> ([f32; 3],) {
        (v.to_array(),)
    }

    pub(crate) fn from_c((v,): ([f32; 3],)) -> Result<Vec3, Failure> {
        Ok(Vec3::from_array(v))
    }
}

/// An optional point as a `uint32_t` flag and a `float[3]` (zero when unset).
pub(crate) struct OptionalPoint;

impl OptionalPoint {
    pub(crate) fn to_c(v: &Option<Vec3>) -> (u32, [f32; 3]) {
        (u32::from(v.is_some()), v.unwrap_or(Vec3::ZERO).to_array())
    }

    pub(crate) fn from_c((enabled, p): (u32, [f32; 3])) -> Result<Option<Vec3>, Failure> {
        Ok((enabled != 0).then(|| Vec3::from_array(p)))
    }
}

/// Whether a C field holds no NaN or infinity (integers always pass).
pub(crate) trait Finite {
    fn finite(&self) -> bool;
}

impl Finite for f32 {
    fn finite(&self) -> bool {
        self.is_finite()
    }
}

impl Finite for [f32; 3] {
    fn finite(&self) -> bool {
        self.iter().all(|x| x.is_finite())
    }
}

impl Finite for u32 {
    fn finite(&self) -> bool {
        true
    }
}

impl Finite for u64 {
    fn finite(&self) -> bool {
        true
    }
}
