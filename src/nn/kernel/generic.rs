//! The instruction-set-independent kernels, written once over [`Simd`], and the portable
//! unit.

use super::Post;

/// A vector unit: the handful of operations the kernels need.
pub(super) trait Simd {
    type V: Copy;
    type M: Copy;
    const LANES: usize;
    /// Rows of the register tile of `gemm_nn`.
    const MR: usize;
    /// Vectors per row of the register tile.
    const NR: usize;
    unsafe fn zero() -> Self::V;
    unsafe fn splat(x: f32) -> Self::V;
    /// The first `n` lanes (n ≤ LANES).
    unsafe fn mask(n: usize) -> Self::M;
    unsafe fn load(p: *const f32) -> Self::V;
    /// Loads the masked lanes; the others are 0 and not read.
    unsafe fn load_m(p: *const f32, m: Self::M) -> Self::V;
    unsafe fn store(p: *mut f32, v: Self::V);
    unsafe fn store_m(p: *mut f32, v: Self::V, m: Self::M);
    /// a·b + c (fused in the SIMD kernels).
    unsafe fn mul_add(a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    unsafe fn add(a: Self::V, b: Self::V) -> Self::V;
    /// max(v, 0), NaN → 0.
    unsafe fn relu(v: Self::V) -> Self::V;
    /// v where act is not ≤ 0, else 0.
    unsafe fn keep(v: Self::V, act: Self::V) -> Self::V;
    /// The sixteen partial sums held in `acc` (16 / LANES vectors) added as
    /// [`tree16`] does, bit for bit.
    unsafe fn reduce16(acc: &[Self::V]) -> f32;
}

#[derive(Clone, Copy)]
pub(super) enum PostPtr {
    Identity,
    Relu,
    Keep(*const f32),
}

/// The epilogue on one scalar at offset `at` of C.
#[inline(always)]
pub(super) fn post_scalar(y: f32, post: Post, at: usize) -> f32 {
    match post {
        Post::Identity => y,
        Post::Relu => relu(y),
        Post::KeepWherePositive(act) => keep(y, act[at]),
    }
}

#[inline(always)]
pub(super) fn relu(y: f32) -> f32 {
    if y > 0.0 {
        y
    } else {
        0.0
    }
}

#[inline(always)]
pub(super) fn keep(y: f32, act: f32) -> f32 {
    if act <= 0.0 {
        0.0
    } else {
        y
    }
}

/// Sum of sixteen partial sums as a tree: 8 apart, then 4, 2, 1.
#[inline(always)]
pub(super) fn tree16(mut x: [f32; 16]) -> f32 {
    for w in [8, 4, 2, 1] {
        for l in 0..w {
            x[l] += x[l + w];
        }
    }
    x[0]
}

/// See [`super::Kernel::gemm_nn`]: column panels of NR vectors, row blocks of MR rows,
/// each an MR × NR register tile over the whole k.
// The raw-pointer inner kernels take BLAS's operands one by one (shape, pointers, strides):
// the safe dispatchers (`Kernel::gemm_nn`, `gemm_nt`) check them, grouped, first. These five
// (here and x86.rs) are the crate's only `too_many_arguments`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) unsafe fn gemm_nn<S: Simd>(
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
    let panel = S::NR * S::LANES;
    let mut j = 0;
    while j < n {
        let width = (n - j).min(panel);
        let nv = width.div_ceil(S::LANES);
        let tail = width - (nv - 1) * S::LANES;
        let bias_j = if bias.is_null() { bias } else { bias.add(j) };
        let mut i = 0;
        while i < m {
            let mr = (m - i).min(S::MR);
            let post_ij = match post {
                PostPtr::Keep(p) => PostPtr::Keep(p.add(i * ldc + j)),
                other => other,
            };
            let args = Tile {
                k,
                a: a.add(i * rsa),
                rsa,
                csa,
                b: b.add(j),
                ldb,
                c: c.add(i * ldc + j),
                ldc,
                tail,
                bias: bias_j,
                post: post_ij,
            };
            run_tile::<S>(mr, nv, tail == S::LANES, args);
            i += mr;
        }
        j += width;
    }
}

/// One `mr` × `nv` register tile of [`gemm_nn`], `full` when its last vector has no tail.
/// A tile whose last vector is full is compiled without masks, so its inner loop holds no
/// branch on the tail (measured: the AVX2 loop had one per k).
#[inline(always)]
unsafe fn run_tile<S: Simd>(mr: usize, nv: usize, full: bool, args: Tile) {
    macro_rules! pick {
        ($(($r:literal, $v:literal)),*) => {
            match (mr, nv, full) {
                $(
                    ($r, $v, true) => tile::<S, $r, $v, true>(args),
                    ($r, $v, false) => tile::<S, $r, $v, false>(args),
                )*
                _ => unreachable!("tile {mr} × {nv} larger than the kernel's"),
            }
        };
    }
    pick!(
        (1, 1),
        (2, 1),
        (3, 1),
        (4, 1),
        (5, 1),
        (6, 1),
        (1, 2),
        (2, 2),
        (3, 2),
        (4, 2),
        (5, 2),
        (6, 2),
        (1, 3),
        (2, 3),
        (3, 3),
        (4, 3),
        (5, 3),
        (6, 3),
        (1, 4),
        (2, 4),
        (3, 4),
        (4, 4),
        (5, 4),
        (6, 4)
    );
}

#[derive(Clone, Copy)]
pub(super) struct Tile {
    k: usize,
    a: *const f32,
    rsa: usize,
    csa: usize,
    b: *const f32,
    ldb: usize,
    c: *mut f32,
    ldc: usize,
    /// Lanes used in the tile's last vector.
    tail: usize,
    bias: *const f32,
    post: PostPtr,
}

/// One MR × (NR vectors) block of C: MR·NR accumulators in registers, one fused
/// multiply-add each per k, then bias and epilogue on the way out. `FULL`: the last vector
/// has all its lanes (no masked loads or stores).
#[inline(always)]
unsafe fn tile<S: Simd, const MR: usize, const NR: usize, const FULL: bool>(t: Tile) {
    debug_assert_eq!(FULL, t.tail == S::LANES);
    let full = FULL;
    let last = S::mask(t.tail);
    let load = |p: *const f32, v: usize| {
        if v + 1 < NR || full {
            S::load(p)
        } else {
            S::load_m(p, last)
        }
    };
    let mut acc = [[S::zero(); NR]; MR];
    let (mut ak, mut bk) = (t.a, t.b);
    for _ in 0..t.k {
        let mut bv = [S::zero(); NR];
        for (v, x) in bv.iter_mut().enumerate() {
            *x = load(bk.add(v * S::LANES), v);
        }
        for (r, row) in acc.iter_mut().enumerate() {
            let x = S::splat(*ak.add(r * t.rsa));
            for (acc, b) in row.iter_mut().zip(&bv) {
                *acc = S::mul_add(x, *b, *acc);
            }
        }
        ak = ak.add(t.csa);
        bk = bk.add(t.ldb);
    }
    for (r, row) in acc.iter().enumerate() {
        for (v, &y) in row.iter().enumerate() {
            let off = r * t.ldc + v * S::LANES;
            let mut y = y;
            if !t.bias.is_null() {
                y = S::add(y, load(t.bias.add(v * S::LANES), v));
            }
            y = match t.post {
                PostPtr::Identity => y,
                PostPtr::Relu => S::relu(y),
                PostPtr::Keep(act) => S::keep(y, load(act.add(off), v)),
            };
            if v + 1 < NR || full {
                S::store(t.c.add(off), y);
            } else {
                S::store_m(t.c.add(off), y, last);
            }
        }
    }
}

/// See [`super::Kernel::gemm_nt`]: DV vectors of LANES lanes hold the sixteen partial
/// sums (DV · LANES = 16); RB rows of A at a time share each load of a row of B.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) unsafe fn gemm_nt<S: Simd, const DV: usize>(
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
    let mut i = 0;
    while i < m {
        let rows = (m - i).min(4);
        match rows {
            4 => nt_rows::<S, DV, 4>(i, k, n, a, lda, b, ldb, c, ldc, bias, post),
            3 => nt_rows::<S, DV, 3>(i, k, n, a, lda, b, ldb, c, ldc, bias, post),
            2 => nt_rows::<S, DV, 2>(i, k, n, a, lda, b, ldb, c, ldc, bias, post),
            _ => nt_rows::<S, DV, 1>(i, k, n, a, lda, b, ldb, c, ldc, bias, post),
        }
        i += rows;
    }
}

/// Rows i..i + RB of C = A·Bᵀ.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
unsafe fn nt_rows<S: Simd, const DV: usize, const RB: usize>(
    i: usize,
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
    debug_assert_eq!(DV * S::LANES, 16);
    let whole = k / 16 * 16;
    for j in 0..n {
        let bj = b.add(j * ldb);
        let mut acc = [[S::zero(); DV]; RB];
        let mut kk = 0;
        while kk < whole {
            for d in 0..DV {
                let o = kk + d * S::LANES;
                let bv = S::load(bj.add(o));
                for (r, acc) in acc.iter_mut().enumerate() {
                    let av = S::load(a.add((i + r) * lda + o));
                    acc[d] = S::mul_add(av, bv, acc[d]);
                }
            }
            kk += 16;
        }
        for d in 0..DV {
            let o = kk + d * S::LANES;
            if o < k {
                let mk = S::mask((k - o).min(S::LANES));
                let bv = S::load_m(bj.add(o), mk);
                for (r, acc) in acc.iter_mut().enumerate() {
                    let av = S::load_m(a.add((i + r) * lda + o), mk);
                    acc[d] = S::mul_add(av, bv, acc[d]);
                }
            }
        }
        for (r, acc) in acc.iter().enumerate() {
            let mut y = S::reduce16(acc);
            if !bias.is_null() {
                y += *bias.add(j);
            }
            let at = (i + r) * ldc + j;
            y = match post {
                PostPtr::Identity => y,
                PostPtr::Relu => relu(y),
                PostPtr::Keep(act) => keep(y, *act.add(at)),
            };
            *c.add(at) = y;
        }
    }
}

/// The portable unit: 8 lanes as plain arrays, unfused multiply-add.
pub(super) struct Portable;

impl Simd for Portable {
    type V = [f32; 8];
    type M = usize;
    const LANES: usize = 8;
    const MR: usize = 4;
    const NR: usize = 2;
    #[inline(always)]
    unsafe fn zero() -> [f32; 8] {
        [0.0; 8]
    }
    #[inline(always)]
    unsafe fn splat(x: f32) -> [f32; 8] {
        [x; 8]
    }
    #[inline(always)]
    unsafe fn mask(n: usize) -> usize {
        n
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> [f32; 8] {
        p.cast::<[f32; 8]>().read_unaligned()
    }
    #[inline(always)]
    unsafe fn load_m(p: *const f32, m: usize) -> [f32; 8] {
        let mut v = [0.0; 8];
        for (l, x) in v.iter_mut().enumerate().take(m) {
            *x = *p.add(l);
        }
        v
    }
    #[inline(always)]
    unsafe fn store(p: *mut f32, v: [f32; 8]) {
        p.cast::<[f32; 8]>().write_unaligned(v)
    }
    #[inline(always)]
    unsafe fn store_m(p: *mut f32, v: [f32; 8], m: usize) {
        for (l, x) in v.iter().enumerate().take(m) {
            *p.add(l) = *x;
        }
    }
    #[inline(always)]
    unsafe fn mul_add(a: [f32; 8], b: [f32; 8], c: [f32; 8]) -> [f32; 8] {
        std::array::from_fn(|l| a[l] * b[l] + c[l])
    }
    #[inline(always)]
    unsafe fn add(a: [f32; 8], b: [f32; 8]) -> [f32; 8] {
        std::array::from_fn(|l| a[l] + b[l])
    }
    #[inline(always)]
    unsafe fn relu(v: [f32; 8]) -> [f32; 8] {
        v.map(relu)
    }
    #[inline(always)]
    unsafe fn keep(v: [f32; 8], act: [f32; 8]) -> [f32; 8] {
        std::array::from_fn(|l| keep(v[l], act[l]))
    }
    #[inline(always)]
    unsafe fn reduce16(acc: &[[f32; 8]]) -> f32 {
        let mut lanes = [0.0; 16];
        lanes[..8].copy_from_slice(&acc[0]);
        lanes[8..].copy_from_slice(&acc[1]);
        tree16(lanes)
    }
}
