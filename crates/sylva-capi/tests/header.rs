//! `include/sylva.h` is what cbindgen makes of this crate's declarations (`cbindgen.toml`):
//! a signature or layout changed in Rust and not in the header fails here.
//! `SYLVA_BLESS=1 cargo test -p sylva-capi --test header` writes the header anew.

use std::path::Path;

#[test]
fn the_c_header_is_generated_from_the_rust_declarations() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen reads the crate");
    let mut made = Vec::new();
    bindings.write(&mut made);
    let header = dir.join("include/sylva.h");
    if std::env::var_os("SYLVA_BLESS").is_some() {
        std::fs::write(&header, &made).expect("write the header");
    }
    let committed = std::fs::read(&header).expect("include/sylva.h");
    assert!(
        committed == made,
        "include/sylva.h is not what cbindgen makes of src/lib.rs; run \
         SYLVA_BLESS=1 cargo test -p sylva-capi --test header and review the change"
    );
}
