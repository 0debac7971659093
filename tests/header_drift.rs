//! The committed `include/plumage.h` must be exactly what cbindgen generates
//! from the sources. To refresh it after changing the C ABI:
//!   cbindgen --config cbindgen.toml --crate plumage --output include/plumage.h
//! or run this test with PLUMAGE_BLESS_HEADER=1.

use std::path::Path;

#[test]
fn committed_header_matches_the_sources() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(root.join("cbindgen.toml")).expect("cbindgen.toml parses");
    let bindings = cbindgen::Builder::new()
        .with_crate(root)
        .with_config(config)
        .generate()
        .expect("cbindgen generates the header");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let path = root.join("include/plumage.h");
    if std::env::var_os("PLUMAGE_BLESS_HEADER").is_some() {
        std::fs::write(&path, &generated).expect("write include/plumage.h");
        return;
    }
    let committed = std::fs::read(&path).expect("include/plumage.h exists");
    assert!(
        committed == generated,
        "include/plumage.h differs from what the sources generate; refresh it with \
         `cbindgen --config cbindgen.toml --crate plumage --output include/plumage.h`"
    );
}

#[test]
fn header_declares_the_contract() {
    let raw = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("include/plumage.h")).unwrap();
    // Compare declarations with whitespace folded and `struct ` tags dropped.
    let header = raw.split_whitespace().collect::<Vec<_>>().join(" ").replace("struct ", "");
    for name in [
        "const char *plumage_version(void)",
        "uint32_t plumage_abi_version(void)",
        "typedef uint32_t PlumageStatus;",
        "const char *plumage_status_name(uint32_t status)",
        "void plumage_config_init(PlumageConfig *cfg)",
        "void plumage_mesh_desc_init(PlumageMeshDesc *mesh)",
        "PlumageStatus plumage_system_create(const PlumageConfig *cfg, const PlumageMeshDesc *rest, PlumageSystem **out)",
        "PlumageStatus plumage_system_destroy(PlumageSystem *sys)",
        "PlumageStatus plumage_system_step(PlumageSystem *sys, const float *positions, size_t vertex_count)",
        "PlumageStatus plumage_system_evaluate(PlumageSystem *sys, const float *positions, size_t vertex_count)",
        "PlumageStatus plumage_system_feather_count(const PlumageSystem *sys, size_t *out)",
        "size_t plumage_system_last_error(const PlumageSystem *sys, char *buf, size_t capacity)",
        "PlumageStatus plumage_system_save_state(const PlumageSystem *sys, uint8_t *buf, size_t capacity, size_t *out_len)",
        "PlumageStatus plumage_system_load_state(PlumageSystem *sys, const uint8_t *blob, size_t len)",
        "PlumageStatus plumage_system_validate(const PlumageSystem *sys, PlumageValidation *out)",
        "PlumageStatus plumage_system_frame_stats(const PlumageSystem *sys, PlumageFrameStats *out)",
        "PlumageStatus plumage_system_feather_instances(const PlumageSystem *sys, PlumageFeatherInstance *buf, size_t capacity, size_t *out_len)",
        "void plumage_feather_template_init(PlumageFeatherTemplate *card)",
        "PlumageStatus plumage_system_feather_template(const PlumageSystem *sys, PlumageFeatherTemplate *card)",
        "PlumageStatus plumage_system_changed_feathers(const PlumageSystem *sys, uint32_t *indices, size_t capacity, size_t *out_len, uint32_t *out_all)",
        "#define PLUMAGE_INSTANCE_BEND_RANGE",
        "#define PLUMAGE_H",
        "Thread safety",
    ] {
        assert!(header.contains(name), "header lacks `{name}`");
    }
}

/// Every macro the header defines carries the `PLUMAGE_` prefix: a host's
/// own `MAX_SEGMENTS` or `BURIAL_TESTS_FLOOR` must not collide with ours.
#[test]
fn every_macro_is_prefixed() {
    let raw = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("include/plumage.h")).unwrap();
    let unprefixed: Vec<&str> = raw
        .lines()
        .filter_map(|l| l.trim_start().strip_prefix("#define "))
        .filter_map(|rest| rest.split_whitespace().next())
        .filter(|name| !name.starts_with("PLUMAGE_"))
        .collect();
    assert!(unprefixed.is_empty(), "unprefixed macros in plumage.h: {unprefixed:?}");
}
