//! Lane-interleaved records to rows: the transposition between a SIMD kernel's layout
//! (value `e` of every lane side by side) and one row per lane (each record's values in
//! order), as a renderer reads them.
//!
//! [`lanes_to_rows`] moves 12-value records (a row-major 3×4 matrix each: the sway step's
//! palettes). On x86-64 with AVX it transposes eight lanes at a time in registers (an 8×8
//! and a 4×8 block per record); elsewhere, or for a width that is not a multiple of 8, it
//! copies value by value. Both move the same bits.

/// Values per record.
pub const RECORD: usize = 12;

/// Copy lane-interleaved 12-value records into one row per lane.
///
/// `block` holds records side by side, each as 12 values × `width` lanes: value `e` of
/// lane `l` in record `r` is `block[(12 r + e) · width + l]`. `rows[l]` receives lane `l`'s
/// first `rows[l].len() / 12` records, each record's 12 values in order; an empty row
/// takes nothing. `rows` may name fewer lanes than `width`.
///
/// # Panics
/// If `rows` names more than `width` lanes, a row's length is not a multiple of 12, or a
/// row asks for more records than `block` holds.
pub fn lanes_to_rows(block: &[f32], width: usize, rows: &mut [&mut [f32]]) {
    assert!(rows.len() <= width, "{} rows for {width} lanes", rows.len());
    let records = rows.iter().map(|r| r.len() / RECORD).max().unwrap_or(0);
    assert!(rows.iter().all(|r| r.len().is_multiple_of(RECORD)), "a row is not whole records");
    assert!(block.len() >= records * RECORD * width, "rows ask for more than the block holds");
    #[cfg(target_arch = "x86_64")]
    if width.is_multiple_of(8) && crate::simd::Level::detect() != crate::simd::Level::Baseline {
        // SAFETY: `detect` found AVX2 (so AVX) on this CPU.
        unsafe { avx::transpose(block, width, records, rows) };
        return;
    }
    scalar(block, width, rows);
}

/// Value by value: the reference the AVX path is tested against.
fn scalar(block: &[f32], width: usize, rows: &mut [&mut [f32]]) {
    for (l, row) in rows.iter_mut().enumerate() {
        for (r, out) in row.chunks_exact_mut(RECORD).enumerate() {
            for (e, x) in out.iter_mut().enumerate() {
                *x = block[(RECORD * r + e) * width + l];
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::RECORD;
    use std::arch::x86_64::*;

    /// Every record the rows ask for (at most `records`), eight lanes at a time: each
    /// record is read once from memory, all its lanes written before the next.
    #[target_feature(enable = "avx")]
    pub(super) fn transpose(block: &[f32], width: usize, records: usize, rows: &mut [&mut [f32]]) {
        for r in 0..records {
            for (h, eight) in rows.chunks_mut(8).enumerate() {
                if eight.iter().all(|row| row.len() < RECORD * (r + 1)) {
                    continue;
                }
                // The record's 12 values of these eight lanes, one register per value.
                let at = RECORD * r * width + 8 * h;
                let src = &block[at..at + (RECORD - 1) * width + 8];
                let v: [__m256; RECORD] = std::array::from_fn(|e| {
                    let lanes = &src[e * width..e * width + 8];
                    // SAFETY: `lanes` is 8 floats in bounds; the load is unaligned.
                    unsafe { _mm256_loadu_ps(lanes.as_ptr()) }
                });
                let head = transpose8(&v);
                let tail = transpose4(&v);
                for (k, row) in eight.iter_mut().enumerate() {
                    if row.len() < RECORD * (r + 1) {
                        continue;
                    }
                    let out = &mut row[RECORD * r..RECORD * (r + 1)];
                    // SAFETY: `out` is 12 floats in bounds: 8 from its start, 4 from its 9th.
                    unsafe {
                        _mm256_storeu_ps(out.as_mut_ptr(), head[k]);
                        _mm_storeu_ps(out[8..].as_mut_ptr(), tail[k]);
                    }
                }
            }
        }
    }

    /// Values 0-7 of eight lanes (`v[e]` holds value `e` of lanes 0-7): lane `k`'s eight
    /// values in register `k`. Pairs of values interleaved, then quads, then halves swapped.
    #[target_feature(enable = "avx")]
    fn transpose8(v: &[__m256; RECORD]) -> [__m256; 8] {
        // Per 128-bit half: lanes k and k+1 (of 0-1 / 4-5, or 2-3 / 6-7), values e and e+1.
        let lo = |a, b| _mm256_unpacklo_ps(a, b);
        let hi = |a, b| _mm256_unpackhi_ps(a, b);
        let (t0, t1, t2, t3) = (lo(v[0], v[1]), hi(v[0], v[1]), lo(v[2], v[3]), hi(v[2], v[3]));
        let (t4, t5, t6, t7) = (lo(v[4], v[5]), hi(v[4], v[5]), lo(v[6], v[7]), hi(v[6], v[7]));
        // Values 0-3 (q0-q3) and 4-7 (q4-q7) of lane k in its low half, lane k+4 in its high.
        let q0 = _mm256_shuffle_ps::<0x44>(t0, t2);
        let q1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
        let q2 = _mm256_shuffle_ps::<0x44>(t1, t3);
        let q3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
        let q4 = _mm256_shuffle_ps::<0x44>(t4, t6);
        let q5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
        let q6 = _mm256_shuffle_ps::<0x44>(t5, t7);
        let q7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
        let low = |a, b| _mm256_permute2f128_ps::<0x20>(a, b);
        let high = |a, b| _mm256_permute2f128_ps::<0x31>(a, b);
        [
            low(q0, q4),
            low(q1, q5),
            low(q2, q6),
            low(q3, q7),
            high(q0, q4),
            high(q1, q5),
            high(q2, q6),
            high(q3, q7),
        ]
    }

    /// Values 8-11 of eight lanes: lane `k`'s four in register `k`.
    #[target_feature(enable = "avx")]
    fn transpose4(v: &[__m256; RECORD]) -> [__m128; 8] {
        let t0 = _mm256_unpacklo_ps(v[8], v[9]);
        let t1 = _mm256_unpackhi_ps(v[8], v[9]);
        let t2 = _mm256_unpacklo_ps(v[10], v[11]);
        let t3 = _mm256_unpackhi_ps(v[10], v[11]);
        // Lane k in the low half, lane k+4 in the high half.
        let q = [
            _mm256_shuffle_ps::<0x44>(t0, t2),
            _mm256_shuffle_ps::<0xEE>(t0, t2),
            _mm256_shuffle_ps::<0x44>(t1, t3),
            _mm256_shuffle_ps::<0xEE>(t1, t3),
        ];
        std::array::from_fn(|k| {
            if k < 4 { _mm256_castps256_ps128(q[k]) } else { _mm256_extractf128_ps::<1>(q[k - 4]) }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SplitMix64;

    /// Every lane's row holds its own values in record order, whatever the width, the
    /// lanes named and the records each asks for; the vector path moves the bits the
    /// value-by-value reference moves.
    #[test]
    fn rows_hold_each_lanes_records_in_order() {
        let mut rng = SplitMix64::new(7);
        for width in [4, 8, 16] {
            let records = 37;
            // Distinct values: value e of lane l in record r is r·1000 + e·100 + l (+ noise
            // bits in the low mantissa so no two are equal by accident).
            let block: Vec<f32> = (0..records * RECORD * width)
                .map(|i| {
                    let (r, e, l) = (i / (RECORD * width), i / width % RECORD, i % width);
                    (r * 1000 + e * 100 + l) as f32 + 0.25
                })
                .collect();
            for used in [1, 3, width / 2, width - 1, width] {
                let wants: Vec<usize> =
                    (0..used).map(|_| (rng.next_u64() % (records as u64 + 1)) as usize).collect();
                let mut fast: Vec<Vec<f32>> =
                    wants.iter().map(|&n| vec![f32::NAN; n * RECORD]).collect();
                let mut slow = fast.clone();
                let mut rows: Vec<&mut [f32]> = fast.iter_mut().map(|r| r.as_mut_slice()).collect();
                lanes_to_rows(&block, width, &mut rows);
                let mut rows: Vec<&mut [f32]> = slow.iter_mut().map(|r| r.as_mut_slice()).collect();
                scalar(&block, width, &mut rows);
                for (l, row) in fast.iter().enumerate() {
                    for (i, &x) in row.iter().enumerate() {
                        let want = ((i / RECORD) * 1000 + (i % RECORD) * 100 + l) as f32 + 0.25;
                        assert_eq!(x, want, "width {width}, lane {l}, value {i}");
                    }
                    assert_eq!(row.len(), wants[l] * RECORD);
                }
                let bits = |rows: &[Vec<f32>]| -> Vec<u32> {
                    rows.iter().flatten().map(|x| x.to_bits()).collect()
                };
                assert_eq!(bits(&fast), bits(&slow), "width {width}, {used} lanes");
            }
        }
    }

    /// A row that asks for more records than the block holds is refused, not read past.
    #[test]
    #[should_panic(expected = "more than the block holds")]
    fn a_row_longer_than_the_block_is_refused() {
        let block = vec![0.0; 2 * RECORD * 8];
        let mut row = vec![0.0; 3 * RECORD];
        lanes_to_rows(&block, 8, &mut [row.as_mut_slice()]);
    }
}
