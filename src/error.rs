//! Errors of the safe Rust API. The FFI layer maps each [`ErrorKind`] to a
//! numbered status code; algorithm modules only ever produce [`Error`].

use std::fmt;

/// What went wrong, as a closed set the C ABI can number.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ErrorKind {
    /// A parameter is out of its documented range.
    InvalidArgument,
    /// The mesh cannot be used (structure, not values).
    InvalidMesh,
    /// A frame's vertex count differs from the rest mesh's.
    VertexCountMismatch,
    /// A position or other value is NaN or infinite.
    NonFinite,
    /// A triangle index is not below the vertex count.
    IndexOutOfRange,
    /// No vertices or no triangles.
    EmptyMesh,
    /// Every triangle is degenerate (zero area or repeated corner).
    DegenerateMesh,
    /// A byte size or count overflows the address space.
    SizeOverflow,
    /// The progress callback asked to stop.
    Interrupted,
    /// A saved state blob is truncated, foreign or of another system.
    InvalidState,
    /// The request is outside the documented limits ([`crate::limits`]):
    /// refused before anything large is allocated.
    LimitExceeded,
}

/// An error with a message meant for a person.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Error {
    kind: ErrorKind,
    message: String,
}

impl Error {
    /// A new error of `kind` with `message`.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        Self { kind, message: message.into() }
    }

    /// The kind, for matching.
    pub fn kind(&self) -> ErrorKind {
        self.kind
    }

    /// The human-readable message.
    pub fn message(&self) -> &str {
        &self.message
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Error {}

/// Shorthand for results of this crate.
pub type Result<T> = std::result::Result<T, Error>;
