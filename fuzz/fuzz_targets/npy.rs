//! `.npy` reader with a valid sidecar: any array bytes are refused or read; never a panic.
#![no_main]
const SIDECAR: &str = include_str!("../seeds/npy_sidecar/f.json");
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(field) = sylva_wind::io::parse_npy(data, SIDECAR, "f.json") {
        assert_eq!(field.data.len(), field.grid.points() * 3 * field.grid.frames);
        // And finite, each sample within the physical bound.
        let bound = sylva_wind::field::MAX_SAMPLE_SPEED as f32;
        assert!(field.data.iter().all(|v| v.is_finite() && v.abs() <= bound));
    }
});
