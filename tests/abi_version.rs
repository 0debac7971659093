//! The version rules of README "ABI versions": the SONAME's number (the
//! crate's MAJOR, given by build.rs) changes exactly when
//! `PLUMAGE_ABI_VERSION` does, so the two may only be bumped together.

use plumage::ffi::{PLUMAGE_ABI_VERSION, plumage_abi_version, plumage_version};
use std::ffi::CStr;

#[test]
fn abi_version_follows_the_major_version() {
    let major: u32 = env!("CARGO_PKG_VERSION_MAJOR").parse().unwrap();
    assert_eq!(
        PLUMAGE_ABI_VERSION,
        major + 1,
        "an incompatible C ABI change bumps PLUMAGE_ABI_VERSION and the crate's MAJOR (the SONAME) together"
    );
    assert_eq!(plumage_abi_version(), PLUMAGE_ABI_VERSION);
}

#[test]
fn version_string_is_the_crate_version() {
    // SAFETY: plumage_version returns a static NUL-terminated string.
    let v = unsafe { CStr::from_ptr(plumage_version()) }.to_str().unwrap();
    assert_eq!(v, env!("CARGO_PKG_VERSION"));
}
