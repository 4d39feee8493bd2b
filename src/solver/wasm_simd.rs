//! Multiply-add on WebAssembly SIMD lanes for the solver's wasm kernels.
//!
//! The app ships the core twice (`www/pkg/`): built for baseline SIMD (`+simd128`, every current
//! browser) and for relaxed SIMD as well (`+relaxed-simd`, in Chromium since version 114). With
//! relaxed SIMD, `acc + p * q` is one `relaxed_madd`: a fused multiply-add where the CPU has one
//! (x86-64 with FMA, ARM64), two instructions otherwise; the rounding may differ from the
//! unfused form in the last bit, which the kernels' f32 sums do not notice (they are accurate to
//! ~1e-7 either way). The worker picks the module (`www/worker.js`).

use core::arch::wasm32::v128;

/// `acc + p * q` on 4 f32 lanes.
#[inline(always)]
pub(crate) fn madd_f32x4(p: v128, q: v128, acc: v128) -> v128 {
    #[cfg(target_feature = "relaxed-simd")]
    {
        core::arch::wasm32::f32x4_relaxed_madd(p, q, acc)
    }
    #[cfg(not(target_feature = "relaxed-simd"))]
    {
        core::arch::wasm32::f32x4_add(acc, core::arch::wasm32::f32x4_mul(p, q))
    }
}

/// `acc - p * q` on 4 f32 lanes (the same as `acc + (-p) * q`, to the bit).
#[inline(always)]
pub(crate) fn nmadd_f32x4(p: v128, q: v128, acc: v128) -> v128 {
    #[cfg(target_feature = "relaxed-simd")]
    {
        core::arch::wasm32::f32x4_relaxed_nmadd(p, q, acc)
    }
    #[cfg(not(target_feature = "relaxed-simd"))]
    {
        core::arch::wasm32::f32x4_sub(acc, core::arch::wasm32::f32x4_mul(p, q))
    }
}

/// `acc + p * q` on 2 f64 lanes.
#[inline(always)]
pub(crate) fn madd_f64x2(p: v128, q: v128, acc: v128) -> v128 {
    #[cfg(target_feature = "relaxed-simd")]
    {
        core::arch::wasm32::f64x2_relaxed_madd(p, q, acc)
    }
    #[cfg(not(target_feature = "relaxed-simd"))]
    {
        core::arch::wasm32::f64x2_add(acc, core::arch::wasm32::f64x2_mul(p, q))
    }
}
