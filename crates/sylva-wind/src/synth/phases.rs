//! The phase streams: each frequency line's key, and the unit phasors drawn from a
//! counter-based hash of (key, index) — one hash a phasor for the separable and dense
//! methods, one for two for the embedding — by integer arithmetic, IEEE adds and
//! multiplies and bit selects, so the same on every machine and in every vector width.

use realfft::num_complex::Complex;
use sylva_core::rng::{GOLDEN, mix64};
use sylva_core::simd_kernel;

use super::C64;
use crate::params::Component;

/// Key of the phase stream of one (seed, component, frequency line).
#[inline]
pub(super) fn line_key(seed: u64, comp: Component, j: usize) -> u64 {
    let s = mix64(seed ^ GOLDEN.wrapping_mul(comp.index() as u64 + 1));
    mix64(s ^ (j as u64).wrapping_mul(0xd6e8_feb8_6659_fd93))
}

/// The unit phasor e^{iφ_jk} of Cholesky column `k` on the line with key `key`.
///
/// φ = 2π u with u the top 53 bits of a hash. cos and sin come from the quarter turn
/// q = round(4u) mod 4 (exact) and the remainder r ∈ [−π/4, π/4] (rounded to f32: the
/// phase is uniform to about 1e-7 rad) through Taylor polynomials in f32. Everything is integer
/// arithmetic, IEEE adds and multiplies and bit selects — no libm, no branch — so the value
/// is the same on every machine and in every vectorised or scalar build of [`phasor_row`].
#[inline(always)]
pub(super) fn phasor(key: u64, k: u64) -> C64 {
    let h = mix64(key.wrapping_add(k.wrapping_mul(GOLDEN)));
    // u = u53 / 2^53; 4u = u53 / 2^51; q = round(4u), r = (4u − q)·π/2.
    let u53 = (h >> 11) as i64;
    let q = (u53 + (1 << 50)) >> 51;
    quarter_turns(
        q as u32,
        (u53 - (q << 51)) as f32 * (std::f32::consts::FRAC_PI_2 / 2_251_799_813_685_248.0),
    )
}

/// Two unit phasors from one hash, 32 bits of phase each (the embedding's: it draws four
/// times as many phasors as the grid has points). The phase of `h32` is 2π·h32/2^32 in
/// steps of 1.5e-9 rad, finer than the f32 remainder's 1e-7; otherwise as [`phasor`].
#[inline(always)]
fn phasor32(h32: u32) -> C64 {
    widen(phasor32_f32(h32))
}

/// [`phasor32`] before widening: the same values in f32.
#[inline(always)]
fn phasor32_f32(h32: u32) -> Complex<f32> {
    // q = round(h32 / 2^30) mod 4 and the remainder h32 − q·2^30 ∈ [−2^29, 2^29), in
    // wrapping 32-bit arithmetic (16 lanes to a vector).
    let q = h32.wrapping_add(1 << 29) >> 30;
    let r = h32.wrapping_sub(q << 30) as i32;
    quarter_turns32(q, r as f32 * (std::f32::consts::FRAC_PI_2 / 1_073_741_824.0))
}

/// An f32 complex widened to f64 (exactly).
#[inline(always)]
fn widen(c: Complex<f32>) -> C64 {
    C64::new(f64::from(c.re), f64::from(c.im))
}

/// e^{i(qπ/2 + r)} for r ∈ [−π/4, π/4], widened (exactly) to f64: see [`quarter_turns32`].
#[inline(always)]
fn quarter_turns(q: u32, r: f32) -> C64 {
    widen(quarter_turns32(q, r))
}

/// e^{i(qπ/2 + r)} for r ∈ [−π/4, π/4]: cos r and sin r by polynomials in f32, then q
/// quarter turns (q mod 4) by bit selects on the f32s.
#[inline(always)]
fn quarter_turns32(q: u32, r: f32) -> Complex<f32> {
    // The remainder in f32: Taylor to r⁸ (cos) and r⁹ (sin) is exact to f32 precision on
    // [−π/4, π/4] (truncation < 3e-8), and twice as many f32 lanes fit a vector.
    let r2 = r * r;
    let c =
        1.0 + r2 * (-1.0 / 2.0 + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40_320.0))));
    let sn = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362_880.0)))));
    // Rotate by q quarter turns: (re, im) = (c, s), (−s, c), (−c, −s), (s, −c) for q = 0…3,
    // as bit selects: swap c and s when q is odd, then flip signs.
    let swap = 0u32.wrapping_sub(q & 1);
    let (cb, sb) = (c.to_bits(), sn.to_bits());
    let a = (cb & !swap) | (sb & swap);
    let b = (sb & !swap) | (cb & swap);
    let neg_re = ((q ^ (q >> 1)) & 1) << 31;
    let neg_im = ((q >> 1) & 1) << 31;
    Complex::new(f32::from_bits(a ^ neg_re), f32::from_bits(b ^ neg_im))
}

simd_kernel! {
    /// x-recursion step of a run of lines of one point row, with fresh phasors:
    /// v_j ← ρ_j v_j + s_j e^{iφ_jk}, or v_j ← e^{iφ_jk} in the first column.
    pub(super) fn phasor_row(keys: &[u64], k: u64, v: &mut [C64], ar: Option<(&[f64], &[f64])>) {
        match ar {
            None => {
                for (o, key) in v.iter_mut().zip(keys) {
                    *o = phasor(*key, k);
                }
            }
            Some((rho, s)) => {
                for (((o, key), r), s) in v.iter_mut().zip(keys).zip(rho).zip(s) {
                    let e = phasor(*key, k);
                    *o = C64::new(o.re * r + e.re * s, o.im * r + e.im * s);
                }
            }
        }
    }
}

/// The phasor of index `k` on the line with key `key` in the embedding's stream: the low
/// (even `k`) or high (odd `k`) half of the hash of k/2.
#[cfg(test)]
#[inline(always)]
pub(super) fn paired_phasor(key: u64, k: u64) -> C64 {
    phasor32(paired_hash(key, k))
}

/// The 32 bits of phase of [`paired_phasor`].
#[inline(always)]
fn paired_hash(key: u64, k: u64) -> u32 {
    let h = mix64(key.wrapping_add((k >> 1).wrapping_mul(GOLDEN)));
    (h >> (32 * (k & 1))) as u32
}

/// out[i] = make(the 32 phase bits of index k0 + i): one hash for each pair; the hashes of
/// 16 pairs are taken first, then their 32 phasors, so each step runs in full vector lanes.
#[inline(always)]
fn span_with<C>(key: u64, k0: u64, out: &mut [C], make: impl Fn(u32) -> C) {
    const PAIRS: usize = 16;
    if out.is_empty() {
        return;
    }
    let (head, rest) = out.split_at_mut(usize::from(k0 % 2 == 1));
    if let Some(o) = head.first_mut() {
        *o = make(paired_hash(key, k0));
    }
    let k1 = k0 + head.len() as u64;
    let last = k1 + rest.len() as u64 - 1;
    let mut blocks = rest.chunks_exact_mut(2 * PAIRS);
    let mut h32 = [0u32; 2 * PAIRS];
    for (b, o) in (&mut blocks).enumerate() {
        let first = k1 / 2 + (b * PAIRS) as u64;
        for (i, h) in h32.chunks_exact_mut(2).enumerate() {
            let v = mix64(key.wrapping_add((first + i as u64).wrapping_mul(GOLDEN)));
            h[0] = v as u32;
            h[1] = (v >> 32) as u32;
        }
        for (o, &h) in o.iter_mut().zip(&h32) {
            *o = make(h);
        }
    }
    let rest = blocks.into_remainder();
    let k2 = last + 1 - rest.len() as u64;
    let mut pairs = rest.chunks_exact_mut(2);
    for (i, o) in (&mut pairs).enumerate() {
        let h = mix64(key.wrapping_add((k2 / 2 + i as u64).wrapping_mul(GOLDEN)));
        o[0] = make(h as u32);
        o[1] = make((h >> 32) as u32);
    }
    let tail = pairs.into_remainder();
    if let Some(o) = tail.first_mut() {
        *o = make(paired_hash(key, last));
    }
}

simd_kernel! {
    /// Consecutive phasors of the embedding's stream: out[i] = paired_phasor(key, k0 + i).
    pub(super) fn phasor_span(key: u64, k0: u64, out: &mut [C64]) {
        span_with(key, k0, out, phasor32)
    }
}

simd_kernel! {
    /// [`phasor_span`] in f32: the same phasors before widening.
    pub(super) fn phasor_span_f32(key: u64, k0: u64, out: &mut [Complex<f32>]) {
        span_with(key, k0, out, phasor32_f32)
    }
}
