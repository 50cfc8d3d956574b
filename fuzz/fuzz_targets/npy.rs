//! `.npy` reader with a valid sidecar: any array bytes are refused or read; never a panic.
#![no_main]
const SIDECAR: &str = include_str!("../seeds/npy_sidecar/f.json");
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(field) = sylva_wind::io::parse_npy(data, SIDECAR, "f.json") {
        assert_eq!(field.data.len(), field.grid.points() * 3 * field.grid.frames);
    }
});
