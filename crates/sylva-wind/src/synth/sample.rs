//! The number types the synthesis writes, and what each does in its own precision.

use realfft::num_complex::Complex;
use sylva_core::simd_kernel;

use super::C64;

/// A number type the synthesis can write (f32 for fields, f64 for reference checks). The
/// coefficients are computed in f64, except the embedding's phasors, their products with
/// its factors and its spatial FFTs, which run in this type (an f32 field keeps f32's
/// precision, and its FFTs run twice as many lanes); the final inverse FFT runs in this
/// type.
pub trait Sample: realfft::FftNum + Default {
    /// Convert from the f64 the synthesis computes in.
    fn from_f64_sample(x: f64) -> Self;
    /// out = v ⊙ sc, narrowed to this type.
    fn scale_into(v: &[C64], sc: &[C64], out: &mut [Complex<Self>]);
    /// out = v ⊙ sc for coefficients already in this type (the product taken in f64).
    fn scale_own_into(v: &[Complex<Self>], sc: &[C64], out: &mut [Complex<Self>]);
    /// Widen to f64.
    fn to_f64_sample(self) -> f64;
    /// `out[2i] = out[2i + 1] = v[i]` narrowed to this type (a real factor beside each complex
    /// value's two parts, so products run in straight vector lanes).
    fn narrow_pairs(v: &[f64], out: &mut [Self]);
    /// The embedding's phasors k0, k0 + 1, … of the line with key `key` in this type (f32:
    /// the f64 phasors' values before widening).
    fn phasors(key: u64, k0: u64, out: &mut [Complex<Self>]);
    /// Row h of the embedding's factored blocks applied to the phasors, in this type.
    fn apply_factor_row(
        lanes: &[Self],
        xi: &[Complex<Self>],
        h: usize,
        w: usize,
        out: &mut [Complex<Self>],
    );
}
impl Sample for f32 {
    fn from_f64_sample(x: f64) -> Self {
        x as f32
    }
    fn scale_into(v: &[C64], sc: &[C64], out: &mut [Complex<f32>]) {
        scale_f32(v, sc, out)
    }
    fn scale_own_into(v: &[Complex<f32>], sc: &[C64], out: &mut [Complex<f32>]) {
        scale_f32_own(v, sc, out)
    }
    fn to_f64_sample(self) -> f64 {
        f64::from(self)
    }
    fn narrow_pairs(v: &[f64], out: &mut [f32]) {
        narrow_pairs_f32(v, out)
    }
    fn phasors(key: u64, k0: u64, out: &mut [Complex<f32>]) {
        super::phases::phasor_span_f32(key, k0, out)
    }
    fn apply_factor_row(
        lanes: &[f32],
        xi: &[Complex<f32>],
        h: usize,
        w: usize,
        out: &mut [Complex<f32>],
    ) {
        super::embed::apply_factor_row_f32(lanes, xi, h, w, out)
    }
}
impl Sample for f64 {
    fn from_f64_sample(x: f64) -> Self {
        x
    }
    fn scale_into(v: &[C64], sc: &[C64], out: &mut [Complex<f64>]) {
        scale_f64(v, sc, out)
    }
    fn scale_own_into(v: &[Complex<f64>], sc: &[C64], out: &mut [Complex<f64>]) {
        scale_f64(v, sc, out)
    }
    fn to_f64_sample(self) -> f64 {
        self
    }
    fn narrow_pairs(v: &[f64], out: &mut [f64]) {
        for (o, &x) in out.chunks_exact_mut(2).zip(v) {
            o.fill(x);
        }
    }
    fn phasors(key: u64, k0: u64, out: &mut [Complex<f64>]) {
        super::phases::phasor_span(key, k0, out)
    }
    fn apply_factor_row(
        lanes: &[f64],
        xi: &[Complex<f64>],
        h: usize,
        w: usize,
        out: &mut [Complex<f64>],
    ) {
        super::embed::apply_factor_row(lanes, xi, h, w, out)
    }
}

simd_kernel! {
    /// Multiply coefficients by a complex factor per line and narrow them to f32.
    fn scale_f32(v: &[C64], sc: &[C64], out: &mut [Complex<f32>]) {
        for ((o, c), s) in out.iter_mut().zip(v).zip(sc) {
            *o = Complex::new((c.re * s.re - c.im * s.im) as f32, (c.re * s.im + c.im * s.re) as f32);
        }
    }
}

simd_kernel! {
    /// Reals narrowed to f32, each twice: out[2i] = out[2i + 1] = v[i].
    fn narrow_pairs_f32(v: &[f64], out: &mut [f32]) {
        for (o, &x) in out.chunks_exact_mut(2).zip(v) {
            o.fill(x as f32);
        }
    }
}

simd_kernel! {
    /// Multiply f32 coefficients by a complex factor per line, in f64, and narrow them back.
    fn scale_f32_own(v: &[Complex<f32>], sc: &[C64], out: &mut [Complex<f32>]) {
        for ((o, c), s) in out.iter_mut().zip(v).zip(sc) {
            let (re, im) = (f64::from(c.re), f64::from(c.im));
            *o = Complex::new((re * s.re - im * s.im) as f32, (re * s.im + im * s.re) as f32);
        }
    }
}

simd_kernel! {
    /// Multiply coefficients by a complex factor per line.
    fn scale_f64(v: &[C64], sc: &[C64], out: &mut [Complex<f64>]) {
        for ((o, c), s) in out.iter_mut().zip(v).zip(sc) {
            *o = Complex::new(c.re * s.re - c.im * s.im, c.re * s.im + c.im * s.re);
        }
    }
}
