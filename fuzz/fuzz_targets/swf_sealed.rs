//! `.swf` reader past its checksum: any bytes, with the CRC-32 they need appended (as an
//! edit that recomputes the checksum leaves them), are refused or read as a field of
//! finite samples within the physical bound; never a panic.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let mut sealed = data.to_vec();
    sealed.extend_from_slice(&crc32fast::hash(data).to_le_bytes());
    if let Ok(field) = sylva_wind::io::parse_swf(&sealed) {
        assert_eq!(field.data.len(), field.grid.points() * 3 * field.grid.frames);
        let bound = sylva_wind::field::MAX_SAMPLE_SPEED as f32;
        assert!(field.data.iter().all(|v| v.is_finite() && v.abs() <= bound));
    }
});
