//! Compile the C host code of the tests (tests/check.c) against the public header, as a C
//! program of an engine would be, into a static library linked into the tests only.

fn main() {
    println!("cargo:rerun-if-changed=tests/check.c");
    println!("cargo:rerun-if-changed=include/sylva.h");
    let out = std::env::var("OUT_DIR").expect("OUT_DIR");
    cc::Build::new()
        .file("tests/check.c")
        .include("include")
        .std("c99")
        .warnings_into_errors(true)
        .flag("-Wall")
        .cargo_metadata(false)
        .compile("sylva_check");
    println!("cargo:rustc-link-arg-tests={out}/libsylva_check.a");
}
