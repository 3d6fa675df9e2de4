//! AVX2 and AVX-512 units, and the `#[target_feature]` entry points that compile the
//! generic kernels for them.

use super::generic::{self, PostPtr, Simd};
use std::arch::x86_64::*;

pub(super) struct Avx2;

impl Simd for Avx2 {
    type V = __m256;
    type M = __m256i;
    const LANES: usize = 8;
    const MR: usize = 6;
    const NR: usize = 2;
    #[inline(always)]
    unsafe fn zero() -> __m256 {
        _mm256_setzero_ps()
    }
    #[inline(always)]
    unsafe fn splat(x: f32) -> __m256 {
        _mm256_set1_ps(x)
    }
    #[inline(always)]
    unsafe fn mask(n: usize) -> __m256i {
        _mm256_cmpgt_epi32(
            _mm256_set1_epi32(n as i32),
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        )
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> __m256 {
        _mm256_loadu_ps(p)
    }
    #[inline(always)]
    unsafe fn load_m(p: *const f32, m: __m256i) -> __m256 {
        _mm256_maskload_ps(p, m)
    }
    #[inline(always)]
    unsafe fn store(p: *mut f32, v: __m256) {
        _mm256_storeu_ps(p, v)
    }
    #[inline(always)]
    unsafe fn store_m(p: *mut f32, v: __m256, m: __m256i) {
        _mm256_maskstore_ps(p, m, v)
    }
    #[inline(always)]
    unsafe fn mul_add(a: __m256, b: __m256, c: __m256) -> __m256 {
        _mm256_fmadd_ps(a, b, c)
    }
    #[inline(always)]
    unsafe fn add(a: __m256, b: __m256) -> __m256 {
        _mm256_add_ps(a, b)
    }
    #[inline(always)]
    unsafe fn relu(v: __m256) -> __m256 {
        // maxps returns its second operand when either is NaN: NaN → 0.
        _mm256_max_ps(v, _mm256_setzero_ps())
    }
    #[inline(always)]
    unsafe fn keep(v: __m256, act: __m256) -> __m256 {
        _mm256_andnot_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(act, _mm256_setzero_ps()), v)
    }
    #[inline(always)]
    unsafe fn reduce16(acc: &[__m256]) -> f32 {
        // Lanes 0..8 in acc[0], 8..16 in acc[1]: x[l] + x[l + 8], then as AVX-512 does.
        reduce8(_mm256_add_ps(acc[0], acc[1]))
    }
}

/// x[l] + x[l + 4], then + 2 apart, then + 1 apart: the last three levels of the tree.
#[inline(always)]
unsafe fn reduce8(s8: __m256) -> f32 {
    let s4 = _mm_add_ps(_mm256_castps256_ps128(s8), _mm256_extractf128_ps::<1>(s8));
    let s2 = _mm_add_ps(s4, _mm_movehl_ps(s4, s4));
    let s1 = _mm_add_ss(s2, _mm_shuffle_ps::<0b01>(s2, s2));
    _mm_cvtss_f32(s1)
}

pub(super) struct Avx512;

impl Simd for Avx512 {
    type V = __m512;
    type M = __mmask16;
    const LANES: usize = 16;
    const MR: usize = 4;
    const NR: usize = 4;
    #[inline(always)]
    unsafe fn zero() -> __m512 {
        _mm512_setzero_ps()
    }
    #[inline(always)]
    unsafe fn splat(x: f32) -> __m512 {
        _mm512_set1_ps(x)
    }
    #[inline(always)]
    unsafe fn mask(n: usize) -> __mmask16 {
        if n >= 16 {
            0xffff
        } else {
            (1u16 << n) - 1
        }
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> __m512 {
        _mm512_loadu_ps(p)
    }
    #[inline(always)]
    unsafe fn load_m(p: *const f32, m: __mmask16) -> __m512 {
        _mm512_maskz_loadu_ps(m, p)
    }
    #[inline(always)]
    unsafe fn store(p: *mut f32, v: __m512) {
        _mm512_storeu_ps(p, v)
    }
    #[inline(always)]
    unsafe fn store_m(p: *mut f32, v: __m512, m: __mmask16) {
        _mm512_mask_storeu_ps(p, m, v)
    }
    #[inline(always)]
    unsafe fn mul_add(a: __m512, b: __m512, c: __m512) -> __m512 {
        _mm512_fmadd_ps(a, b, c)
    }
    #[inline(always)]
    unsafe fn add(a: __m512, b: __m512) -> __m512 {
        _mm512_add_ps(a, b)
    }
    #[inline(always)]
    unsafe fn relu(v: __m512) -> __m512 {
        _mm512_max_ps(v, _mm512_setzero_ps())
    }
    #[inline(always)]
    unsafe fn keep(v: __m512, act: __m512) -> __m512 {
        let le = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(act, _mm512_setzero_ps());
        _mm512_mask_mov_ps(v, le, _mm512_setzero_ps())
    }
    #[inline(always)]
    unsafe fn reduce16(acc: &[__m512]) -> f32 {
        // Lanes 8..16 moved down (128-bit blocks 2, 3 → 0, 1): x[l] + x[l + 8].
        let v = acc[0];
        let s8 = _mm512_add_ps(v, _mm512_shuffle_f32x4::<0b11_10_11_10>(v, v));
        reduce8(_mm512_castps512_ps256(s8))
    }
}

/// An 8 × 8 block transpose in AVX registers: rows of `src` (stride `ls`) become columns
/// of `dst` (stride `ld`).
#[inline(always)]
unsafe fn t8x8(src: *const f32, ls: usize, dst: *mut f32, ld: usize) {
    let r: [__m256; 8] = std::array::from_fn(|i| _mm256_loadu_ps(src.add(i * ls)));
    let t0 = _mm256_unpacklo_ps(r[0], r[1]);
    let t1 = _mm256_unpackhi_ps(r[0], r[1]);
    let t2 = _mm256_unpacklo_ps(r[2], r[3]);
    let t3 = _mm256_unpackhi_ps(r[2], r[3]);
    let t4 = _mm256_unpacklo_ps(r[4], r[5]);
    let t5 = _mm256_unpackhi_ps(r[4], r[5]);
    let t6 = _mm256_unpacklo_ps(r[6], r[7]);
    let t7 = _mm256_unpackhi_ps(r[6], r[7]);
    // Columns (0 | 4), (1 | 5), (2 | 6), (3 | 7) of rows 0–3 and of rows 4–7.
    let u0 = _mm256_shuffle_ps::<0x44>(t0, t2);
    let u1 = _mm256_shuffle_ps::<0xee>(t0, t2);
    let u2 = _mm256_shuffle_ps::<0x44>(t1, t3);
    let u3 = _mm256_shuffle_ps::<0xee>(t1, t3);
    let u4 = _mm256_shuffle_ps::<0x44>(t4, t6);
    let u5 = _mm256_shuffle_ps::<0xee>(t4, t6);
    let u6 = _mm256_shuffle_ps::<0x44>(t5, t7);
    let u7 = _mm256_shuffle_ps::<0xee>(t5, t7);
    let cols = [
        _mm256_permute2f128_ps::<0x20>(u0, u4),
        _mm256_permute2f128_ps::<0x20>(u1, u5),
        _mm256_permute2f128_ps::<0x20>(u2, u6),
        _mm256_permute2f128_ps::<0x20>(u3, u7),
        _mm256_permute2f128_ps::<0x31>(u0, u4),
        _mm256_permute2f128_ps::<0x31>(u1, u5),
        _mm256_permute2f128_ps::<0x31>(u2, u6),
        _mm256_permute2f128_ps::<0x31>(u3, u7),
    ];
    for (j, c) in cols.iter().enumerate() {
        _mm256_storeu_ps(dst.add(j * ld), *c);
    }
}

/// `dst` (cols × rows) = `src` (rows × cols)ᵀ: 8 × 8 blocks in registers, the ragged
/// edges element by element.
///
/// # Safety
/// AVX must be available; `src` and `dst` must hold rows · cols values.
#[target_feature(enable = "avx")]
pub(super) unsafe fn transpose_avx(rows: usize, cols: usize, src: *const f32, dst: *mut f32) {
    let (r8, c8) = (rows / 8 * 8, cols / 8 * 8);
    for i in (0..r8).step_by(8) {
        for j in (0..c8).step_by(8) {
            t8x8(src.add(i * cols + j), cols, dst.add(j * rows + i), rows);
        }
    }
    for i in 0..rows {
        let from = if i < r8 { c8 } else { 0 };
        for j in from..cols {
            *dst.add(j * rows + i) = *src.add(i * cols + j);
        }
    }
}

macro_rules! entry {
    ($feat:literal, $unit:ty, $nn:ident, $nt:ident, $dv:literal, $ew:ident) => {
        // As generic.rs's inner kernels: BLAS's operands one by one, checked by the caller.
        #[allow(clippy::too_many_arguments)]
        #[target_feature(enable = $feat)]
        pub(super) unsafe fn $nn(
            m: usize,
            k: usize,
            n: usize,
            a: *const f32,
            rsa: usize,
            csa: usize,
            b: *const f32,
            ldb: usize,
            c: *mut f32,
            ldc: usize,
            bias: *const f32,
            post: PostPtr,
        ) {
            generic::gemm_nn::<$unit>(m, k, n, a, rsa, csa, b, ldb, c, ldc, bias, post)
        }

        #[allow(clippy::too_many_arguments)]
        #[target_feature(enable = $feat)]
        pub(super) unsafe fn $nt(
            m: usize,
            k: usize,
            n: usize,
            a: *const f32,
            lda: usize,
            b: *const f32,
            ldb: usize,
            c: *mut f32,
            ldc: usize,
            bias: *const f32,
            post: PostPtr,
        ) {
            generic::gemm_nt::<$unit, $dv>(m, k, n, a, lda, b, ldb, c, ldc, bias, post)
        }

        /// Runs `f` (inlined) compiled for this instruction set.
        #[target_feature(enable = $feat)]
        #[inline]
        pub(super) unsafe fn $ew<R>(f: impl FnOnce() -> R) -> R {
            f()
        }
    };
}

entry!(
    "avx2,fma",
    Avx2,
    gemm_nn_avx2,
    gemm_nt_avx2,
    2,
    avx2_elementwise
);
entry!(
    "avx512f",
    Avx512,
    gemm_nn_avx512,
    gemm_nt_avx512,
    1,
    avx512_elementwise
);
