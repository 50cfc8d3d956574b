//! TurbSim `.bts` reader: any bytes are refused or read; never a panic.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(f) = sylva_wind::io::parse_bts(data) {
        assert_eq!(f.grid.len(), f.frames * f.nz * f.ny * 3);
        assert_eq!(f.tower.len(), f.frames * f.tower_points * 3);
        assert!(f.grid.iter().chain(&f.tower).all(|v| v.is_finite()));
    }
});
