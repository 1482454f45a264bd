//! `W x` for AVX2, four rows at a time, with [`super::linalg::dot`]'s bits in every row.
//!
//! One row's dot keeps eight partial sums (lane `k` sums the products of columns `k mod 8`): two
//! four-lane vectors, so a row alone is two dependent add chains that wait on the adder's
//! latency. Four rows side by side give eight independent chains and load each chunk of `x`
//! once for all four. Each row still sees exactly its own products added in its own order, and
//! the same final reduction, so each output has the portable bits (no FMA: `V3` only offers
//! it; here a multiply and an add stay two roundings).

use pulp::{f64x4, x86::V3};

use super::linalg::dot;

/// Rows a step takes at once.
const ROWS: usize = 4;

/// The two four-lane halves of an eight-column chunk.
#[inline(always)]
fn halves(c: &[f64; 8]) -> (f64x4, f64x4) {
    (f64x4(c[0], c[1], c[2], c[3]), f64x4(c[4], c[5], c[6], c[7]))
}

/// [`dot`] of [`ROWS`] rows (each `x.len()` long) with `x`.
#[inline(always)]
fn dot_rows(s: V3, rows: [&[f64]; ROWS], x: &[f64]) -> [f64; ROWS] {
    let (x8, x_tail) = x.as_chunks::<8>();
    let m = x8.len();
    let w8 = rows.map(|r| &r.as_chunks::<8>().0[..m]);
    let zero = s.splat_f64x4(0.0);
    let (mut lo, mut hi) = ([zero; ROWS], [zero; ROWS]);
    for (j, xc) in x8.iter().enumerate() {
        let (xl, xh) = halves(xc);
        for r in 0..ROWS {
            let (wl, wh) = halves(&w8[r][j]);
            lo[r] = s.add_f64x4(lo[r], s.mul_f64x4(wl, xl));
            hi[r] = s.add_f64x4(hi[r], s.mul_f64x4(wh, xh));
        }
    }
    let n = 8 * m;
    std::array::from_fn(|r| {
        // Lane k holds acc[k] + acc[k + 4], the pairs `dot` adds first.
        let f64x4(p0, p1, p2, p3) = s.add_f64x4(lo[r], hi[r]);
        let mut tail = 0.0;
        for (w, xv) in rows[r][n..].iter().zip(x_tail) {
            tail += w * xv;
        }
        ((p0 + p1) + (p2 + p3)) + tail
    })
}

/// `y = W x`, `W` row-major `y.len() x x.len()`: each output has [`dot`]'s bits.
#[inline(always)]
pub(super) fn matvec(s: V3, w: &[f64], x: &[f64], y: &mut [f64]) {
    let cols = x.len();
    let mut blocks = w.chunks_exact(ROWS * cols);
    let mut ys = y.chunks_exact_mut(ROWS);
    for (block, yb) in (&mut blocks).zip(&mut ys) {
        let rows: [&[f64]; ROWS] = std::array::from_fn(|r| &block[r * cols..(r + 1) * cols]);
        yb.copy_from_slice(&dot_rows(s, rows, x));
    }
    for (row, yi) in blocks
        .remainder()
        .chunks_exact(cols)
        .zip(ys.into_remainder())
    {
        *yi = dot(row, x);
    }
}
