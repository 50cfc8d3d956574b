//! `.npy` sidecar (JSON): any sidecar text beside a valid array is refused or read.
#![no_main]
const ARRAY: &[u8] = include_bytes!("../seeds/npy/f.npy");
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(field) = sylva_wind::io::parse_npy(ARRAY, &text, "f.json") {
        assert_eq!(field.data.len(), field.grid.points() * 3 * field.grid.frames);
        // And finite, each sample within the physical bound.
        let bound = sylva_wind::field::MAX_SAMPLE_SPEED as f32;
        assert!(field.data.iter().all(|v| v.is_finite() && v.abs() <= bound));
    }
});
