//! `.swf` reader: any bytes are refused with an error or read; never a panic.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(field) = sylva_wind::io::parse_swf(data) {
        // What is read is consistent with its grid.
        assert_eq!(field.data.len(), field.grid.points() * 3 * field.grid.frames);
        // And finite, each sample within the physical bound.
        let bound = sylva_wind::field::MAX_SAMPLE_SPEED as f32;
        assert!(field.data.iter().all(|v| v.is_finite() && v.abs() <= bound));
    }
});
