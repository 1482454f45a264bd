//! One sample of every channel through the filter cascade: scipy `sosfilt`'s transposed direct
//! form II, term for term, with the delay registers laid out `[section][channel]`.
//!
//! Lanes are channels, so however wide the vectors, each channel sees the same operations in
//! the same order. The portable loop runs over the channels and lets the compiler vectorise
//! it. On x86_64 with AVX2 and 4, 8, 12 or 16 channels an explicit kernel keeps the sample in
//! four-lane registers from section to section (the compiler left a 12-wide loop scalar); it
//! does exactly the portable loop's multiplies, adds and subtracts (no fused multiply-add), so
//! the bits are the same, which the chain's tests check against the portable build.

use super::simd::Simd;
use super::sos::Sos;

/// `work` (one value per channel) through `cascade` in place; `z0`, `z1` are the delay
/// registers `[section][channel]`, as long as `cascade.len() * work.len()`.
#[inline(always)]
pub(super) fn run_cascade(
    simd: Simd,
    cascade: &[Sos],
    work: &mut [f64],
    z0: &mut [f64],
    z1: &mut [f64],
) {
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = simd.x86_v3() {
        let done = v3.vectorize(
            #[inline(always)]
            || match work.len() {
                4 => x86::cascade::<1>(v3, cascade, work, z0, z1),
                8 => x86::cascade::<2>(v3, cascade, work, z0, z1),
                12 => x86::cascade::<3>(v3, cascade, work, z0, z1),
                16 => x86::cascade::<4>(v3, cascade, work, z0, z1),
                _ => false,
            },
        );
        if done {
            return;
        }
    }
    simd.run(
        #[inline(always)]
        || portable(cascade, work, z0, z1),
    );
}

/// The loop over the channels, section by section.
#[inline(always)]
fn portable(cascade: &[Sos], work: &mut [f64], z0: &mut [f64], z1: &mut [f64]) {
    let n = work.len();
    for (s, section) in cascade.iter().enumerate() {
        let [b0, b1, b2] = section.b;
        let [_, a1, a2] = section.a;
        let z0 = &mut z0[s * n..(s + 1) * n];
        let z1 = &mut z1[s * n..(s + 1) * n];
        for ((x, z0), z1) in work.iter_mut().zip(z0).zip(z1) {
            let xin = *x;
            let y = b0 * xin + *z0;
            *z0 = b1 * xin - a1 * y + *z1;
            *z1 = b2 * xin - a2 * y;
            *x = y;
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use pulp::{f64x4, x86::V3};

    use super::Sos;

    fn load(v: &[f64; 4]) -> f64x4 {
        f64x4(v[0], v[1], v[2], v[3])
    }

    fn store(v: f64x4, out: &mut [f64; 4]) {
        *out = [v.0, v.1, v.2, v.3];
    }

    /// [`super::portable`] for exactly `4 * V` channels, `V` four-lane vectors wide; false
    /// (nothing done) for another width.
    #[inline(always)]
    pub(super) fn cascade<const V: usize>(
        s: V3,
        cascade: &[Sos],
        work: &mut [f64],
        z0: &mut [f64],
        z1: &mut [f64],
    ) -> bool {
        let n = 4 * V;
        let (work4, []) = work.as_chunks_mut::<4>() else {
            return false;
        };
        if work4.len() != V || z0.len() != n * cascade.len() || z1.len() != n * cascade.len() {
            return false;
        }
        let (z0, _) = z0.as_chunks_mut::<4>();
        let (z1, _) = z1.as_chunks_mut::<4>();
        let mut x: [f64x4; V] = std::array::from_fn(|v| load(&work4[v]));
        for ((section, z0), z1) in cascade
            .iter()
            .zip(z0.chunks_exact_mut(V))
            .zip(z1.chunks_exact_mut(V))
        {
            let [b0, b1, b2] = section.b.map(|c| s.splat_f64x4(c));
            let [_, a1, a2] = section.a.map(|c| s.splat_f64x4(c));
            for ((xv, z0), z1) in x.iter_mut().zip(z0).zip(z1) {
                let xin = *xv;
                // y = b0 x + z0; z0' = (b1 x - a1 y) + z1; z1' = b2 x - a2 y.
                let y = s.add_f64x4(s.mul_f64x4(b0, xin), load(z0));
                let z0_next = s.add_f64x4(
                    s.sub_f64x4(s.mul_f64x4(b1, xin), s.mul_f64x4(a1, y)),
                    load(z1),
                );
                store(z0_next, z0);
                store(s.sub_f64x4(s.mul_f64x4(b2, xin), s.mul_f64x4(a2, y)), z1);
                *xv = y;
            }
        }
        for (out, v) in work4.iter_mut().zip(x) {
            store(v, out);
        }
        true
    }
}
