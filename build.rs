//! Gives the shared library (cdylib) its SONAME on ELF platforms, so an
//! installed `libplumage.so.MAJOR.MINOR.PATCH` is found by programs through
//! `libplumage.so.MAJOR` (README, "Installing"). Only the cdylib's link line
//! changes: the rlib and staticlib, and so every Rust test, are untouched.

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let elf = matches!(
        os.as_str(),
        "linux" | "android" | "freebsd" | "netbsd" | "openbsd" | "dragonfly" | "illumos" | "solaris"
    );
    if elf {
        let major = std::env::var("CARGO_PKG_VERSION_MAJOR").expect("cargo sets CARGO_PKG_VERSION_MAJOR");
        println!("cargo::rustc-cdylib-link-arg=-Wl,-soname,libplumage.so.{major}");
    }
}
