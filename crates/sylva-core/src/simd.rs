//! One CPU-feature dispatch for Sylva's hot loops.
//!
//! [`simd_kernel!`](crate::simd_kernel) defines a function three times — for AVX-512 (F, DQ,
//! VL), AVX2 and the baseline — from one body, and calls the widest the CPU has. The body
//! uses plain IEEE adds and multiplies (Rust never fuses them into FMAs), so every variant
//! gives the same bits: only the speed differs. std caches the feature checks.

/// The widest instruction set the kernels use on this CPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// AVX-512 F, DQ and VL.
    Avx512,
    /// AVX2.
    Avx2,
    /// The target's baseline (SSE2 on x86-64, or another architecture).
    Baseline,
}

impl Level {
    /// What this CPU offers.
    pub fn detect() -> Level {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512dq")
                && std::arch::is_x86_feature_detected!("avx512vl")
            {
                return Level::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                return Level::Avx2;
            }
        }
        Level::Baseline
    }

    /// Its name, as benchmarks print it.
    pub fn name(self) -> &'static str {
        match self {
            Level::Avx512 => "AVX-512",
            Level::Avx2 => "AVX2",
            Level::Baseline => "baseline",
        }
    }
}

/// Define `fn $name(args) body` compiled three times (AVX-512, AVX2, baseline), calling the
/// widest variant [`Level::detect`] finds. Arguments are plain identifiers with types. One
/// `const` generic parameter is allowed (`fn name<const W: usize>(…)`): each width a caller
/// names is then compiled three times.
#[macro_export]
macro_rules! simd_kernel {
    ($(#[$m:meta])* $vis:vis fn $name:ident<const $g:ident: $gt:ty>($($a:ident: $t:ty),* $(,)?) $body:block) => {
        $(#[$m])*
        $vis fn $name<const $g: $gt>($($a: $t),*) {
            #[inline(always)]
            fn imp<const $g: $gt>($($a: $t),*) $body
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
            fn wide<const $g: $gt>($($a: $t),*) {
                imp::<$g>($($a),*)
            }
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2")]
            fn avx2<const $g: $gt>($($a: $t),*) {
                imp::<$g>($($a),*)
            }
            #[cfg(target_arch = "x86_64")]
            match $crate::simd::Level::detect() {
                // SAFETY: `detect` found these AVX-512 subsets on this CPU.
                $crate::simd::Level::Avx512 => return unsafe { wide::<$g>($($a),*) },
                // SAFETY: `detect` found AVX2 on this CPU.
                $crate::simd::Level::Avx2 => return unsafe { avx2::<$g>($($a),*) },
                $crate::simd::Level::Baseline => {}
            }
            imp::<$g>($($a),*)
        }
    };
    ($(#[$m:meta])* $vis:vis fn $name:ident($($a:ident: $t:ty),* $(,)?) $body:block) => {
        $(#[$m])*
        $vis fn $name($($a: $t),*) {
            #[inline(always)]
            fn imp($($a: $t),*) $body
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
            fn wide($($a: $t),*) {
                imp($($a),*)
            }
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2")]
            fn avx2($($a: $t),*) {
                imp($($a),*)
            }
            #[cfg(target_arch = "x86_64")]
            match $crate::simd::Level::detect() {
                // SAFETY: `detect` found these AVX-512 subsets on this CPU.
                $crate::simd::Level::Avx512 => return unsafe { wide($($a),*) },
                // SAFETY: `detect` found AVX2 on this CPU.
                $crate::simd::Level::Avx2 => return unsafe { avx2($($a),*) },
                $crate::simd::Level::Baseline => {}
            }
            imp($($a),*)
        }
    };
}

/// A hint that `slice[i]` will be read soon: its cache line is requested now (nothing where
/// `i` is out of range, or off x86-64). It changes no memory and no result.
#[inline(always)]
pub fn prefetch<T>(slice: &[T], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(r) = slice.get(i) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: SSE is part of x86-64's baseline; a prefetch never faults and writes
        // nothing, and the address is in bounds.
        unsafe { _mm_prefetch::<_MM_HINT_T0>((r as *const T).cast::<i8>()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (slice, i);
}

#[cfg(test)]
mod tests {
    /// Every variant gives the same bits: the dispatched kernel equals the plain loop.
    #[test]
    fn the_dispatched_kernel_matches_the_plain_loop() {
        crate::simd_kernel! {
            fn axpy(a: f32, x: &[f32], y: &mut [f32]) {
                for (yi, xi) in y.iter_mut().zip(x) {
                    *yi += a * *xi;
                }
            }
        }
        let x: Vec<f32> = (0..1000).map(|i| (i as f32 * 0.37).sin()).collect();
        let mut y: Vec<f32> = (0..1000).map(|i| (i as f32 * 0.11).cos()).collect();
        let mut want = y.clone();
        for (w, xi) in want.iter_mut().zip(&x) {
            *w += 1.7 * *xi;
        }
        axpy(1.7, &x, &mut y);
        assert!(y.iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert!(!super::Level::detect().name().is_empty());
    }
}
