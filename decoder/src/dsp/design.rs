//! Filter design in code: Butterworth band-pass as second-order sections, the first-order DC
//! high-pass and the mains notch, each reproducing scipy's algorithm step by step (scipy 1.17
//! `butter`/`iirfilter`, `lp2bp_zpk`, `bilinear_zpk`, `zpk2sos(pairing='nearest')`, `iirnotch`)
//! so the coefficients agree with scipy's to rounding (about 1e-15).
//!
//! The functions take frequencies in Hz and trust their arguments: [`crate::dsp::ChainConfig`]
//! validates them (`0 < lo < hi < fs/2`, order >= 1) before they are called.

use super::sos::Sos;
use std::f64::consts::PI;

/// A minimal complex number for the pole/zero algebra of the design step.
#[derive(Debug, Clone, Copy, PartialEq)]
struct C {
    re: f64,
    im: f64,
}

impl C {
    const fn new(re: f64, im: f64) -> Self {
        C { re, im }
    }
    fn real(re: f64) -> Self {
        C { re, im: 0.0 }
    }
    fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn scale(self, k: f64) -> C {
        C::new(self.re * k, self.im * k)
    }
    fn conj(self) -> C {
        C::new(self.re, -self.im)
    }
    fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }
    /// Smith's algorithm: no overflow for large operands, the way numpy divides.
    fn div(self, o: C) -> C {
        if o.re.abs() >= o.im.abs() {
            let r = o.im / o.re;
            let d = o.re + o.im * r;
            C::new((self.re + self.im * r) / d, (self.im - self.re * r) / d)
        } else {
            let r = o.re / o.im;
            let d = o.re * r + o.im;
            C::new((self.re * r + self.im) / d, (self.im * r - self.re) / d)
        }
    }
    /// Principal square root (non-negative real part), as C99 `csqrt`.
    fn sqrt(self) -> C {
        if self.re == 0.0 && self.im == 0.0 {
            return C::new(0.0, self.im);
        }
        let m = self.abs();
        if self.re >= 0.0 {
            let t = ((m + self.re) * 0.5).sqrt();
            C::new(t, self.im / (2.0 * t))
        } else {
            let t = ((m - self.re) * 0.5).sqrt();
            C::new(self.im.abs() / (2.0 * t), t.copysign(self.im))
        }
    }
    fn is_real(self) -> bool {
        self.im == 0.0
    }
}

/// Butterworth band-pass of `order` between `lo_hz` and `hi_hz` at `fs_hz`, as second-order
/// sections: `scipy.signal.butter(order, [lo, hi], 'bandpass', fs=fs, output='sos')`.
///
/// The result has `order` sections; the overall gain sits in the first one, and sections are
/// ordered with the poles closest to the unit circle last, as scipy orders them.
pub fn butter_bandpass(order: usize, lo_hz: f64, hi_hz: f64, fs_hz: f64) -> Vec<Sos> {
    let n = order;
    // Analog prototype (buttap): poles on the left unit half-circle, no zeros, gain 1.
    let p_proto: Vec<C> = (0..n)
        .map(|i| {
            let m = -(n as f64) + 1.0 + 2.0 * i as f64;
            let theta = PI * m / (2.0 * n as f64);
            C::new(-theta.cos(), -theta.sin())
        })
        .collect();

    // Prewarp the normalised edges (iirfilter with its internal fs = 2).
    let warp = |f: f64| {
        let wn = 2.0 * f / fs_hz;
        2.0 * 2.0 * (PI * wn / 2.0).tan()
    };
    let (w1, w2) = (warp(lo_hz), warp(hi_hz));
    let bw = w2 - w1;
    let wo = (w1 * w2).sqrt();

    // lp2bp_zpk: every low-pass pole splits into two band-pass poles; n zeros at s = 0.
    let wo2 = C::real(wo * wo);
    let p_lp: Vec<C> = p_proto.iter().map(|p| p.scale(bw / 2.0)).collect();
    let mut p_bp = Vec::with_capacity(2 * n);
    for &p in &p_lp {
        p_bp.push(p.add(p.mul(p).sub(wo2).sqrt()));
    }
    for &p in &p_lp {
        p_bp.push(p.sub(p.mul(p).sub(wo2).sqrt()));
    }
    let z_bp = vec![C::real(0.0); n];
    let k_bp = bw.powi(n as i32);

    // bilinear_zpk with fs = 2: s-plane zeros/poles to z-plane, the n zeros at infinity go to
    // Nyquist (z = -1).
    let fs2 = C::real(4.0);
    let mut z_z: Vec<C> = z_bp.iter().map(|&z| fs2.add(z).div(fs2.sub(z))).collect();
    z_z.extend(std::iter::repeat_n(C::real(-1.0), n));
    let p_z: Vec<C> = p_bp.iter().map(|&p| fs2.add(p).div(fs2.sub(p))).collect();
    let num = z_bp
        .iter()
        .fold(C::real(1.0), |acc, &z| acc.mul(fs2.sub(z)));
    let den = p_bp
        .iter()
        .fold(C::real(1.0), |acc, &p| acc.mul(fs2.sub(p)));
    let k_z = k_bp * num.div(den).re;

    zpk2sos_nearest(z_z, p_z, k_z)
}

/// The DC-removal stage: first-order Butterworth high-pass at `fc_hz`, as one section
/// `[g, -g, 0, 1, -R, 0]`: `scipy.signal.butter(1, fc, 'highpass', fs=fs, output='sos')`.
pub fn dc_highpass(fc_hz: f64, fs_hz: f64) -> Sos {
    // buttap(1) -> lp2hp (pole at -wo, zero at 0) -> bilinear with fs = 2, done in closed form.
    let wo = 4.0 * (PI * (2.0 * fc_hz / fs_hz) / 2.0).tan();
    let pole = (4.0 - wo) / (4.0 + wo);
    let gain = 4.0 / (4.0 + wo);
    Sos {
        b: [gain, -gain, 0.0],
        a: [1.0, -pole, 0.0],
    }
}

/// Second-order IIR notch at `f0_hz` with quality factor `q`: `scipy.signal.iirnotch(f0, q,
/// fs=fs)` (-3 dB bandwidth `f0 / q`, unity gain far from `f0`).
pub fn iirnotch(f0_hz: f64, q: f64, fs_hz: f64) -> Sos {
    let w0 = 2.0 * f0_hz / fs_hz;
    let bw = w0 / q * PI;
    let w0 = w0 * PI;
    let beta = (bw / 2.0).tan();
    let gain = 1.0 / (1.0 + beta);
    Sos {
        b: [gain, gain * (-2.0 * w0.cos()), gain],
        a: [1.0, -2.0 * gain * w0.cos(), 2.0 * gain - 1.0],
    }
}

/// scipy's `_cplxreal`: complex roots of conjugate pairs (one per pair, positive imaginary part,
/// averaged with its partner) followed by the real roots, each group sorted by real part.
fn cplxreal(mut z: Vec<C>) -> Vec<C> {
    let tol = 100.0 * f64::EPSILON;
    z.sort_by(|a, b| {
        a.re.total_cmp(&b.re)
            .then(a.im.abs().total_cmp(&b.im.abs()))
    });
    let is_real = |c: &C| c.im.abs() <= tol * c.abs();
    let zr: Vec<C> = z
        .iter()
        .filter(|c| is_real(c))
        .map(|c| C::real(c.re))
        .collect();
    let mut zp: Vec<C> = z
        .iter()
        .filter(|c| !is_real(c) && c.im > 0.0)
        .copied()
        .collect();
    let mut zn: Vec<C> = z
        .iter()
        .filter(|c| !is_real(c) && c.im < 0.0)
        .copied()
        .collect();
    // The design only produces conjugate-symmetric sets; a lone complex root would be a bug here.
    assert_eq!(zp.len(), zn.len(), "unpaired complex root in filter design");
    // Runs of (nearly) equal real part are ordered by |imag| so partners line up.
    let mut start = 0;
    while start < zp.len() {
        let mut stop = start + 1;
        while stop < zp.len() && zp[stop].re - zp[stop - 1].re <= tol * zp[stop - 1].abs() {
            stop += 1;
        }
        zp[start..stop].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
        zn[start..stop].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
        start = stop;
    }
    let mut out: Vec<C> = zp
        .iter()
        .zip(&zn)
        .map(|(p, n)| p.add(n.conj()).scale(0.5))
        .collect();
    out.extend(zr);
    out
}

/// Index of the element closest to the unit circle (first on ties, as `np.argmin`).
fn idx_worst(p: &[C]) -> usize {
    let mut best = 0;
    let mut best_d = f64::INFINITY;
    for (i, c) in p.iter().enumerate() {
        let d = (1.0 - c.abs()).abs();
        if d < best_d {
            best_d = d;
            best = i;
        }
    }
    best
}

#[derive(Clone, Copy, PartialEq)]
enum Which {
    Real,
    Complex,
    Any,
}

/// scipy's `_nearest_real_complex_idx`: the closest element of `fro` to `to` of the wanted kind.
fn nearest_idx(fro: &[C], to: C, which: Which) -> usize {
    let mut order: Vec<usize> = (0..fro.len()).collect();
    order.sort_by(|&a, &b| fro[a].sub(to).abs().total_cmp(&fro[b].sub(to).abs()));
    order
        .into_iter()
        .find(|&i| match which {
            Which::Any => true,
            Which::Real => fro[i].is_real(),
            Which::Complex => !fro[i].is_real(),
        })
        .unwrap_or(0)
}

/// Coefficients of the monic polynomial with the given roots (`np.poly`), real part.
fn poly(roots: &[C]) -> Vec<f64> {
    let mut a = vec![C::real(1.0)];
    for &r in roots {
        let mut next = vec![C::real(0.0); a.len() + 1];
        for (i, &c) in a.iter().enumerate() {
            next[i] = next[i].add(c);
            next[i + 1] = next[i + 1].sub(c.mul(r));
        }
        a = next;
    }
    a.iter().map(|c| c.re).collect()
}

/// scipy's `_single_zpksos`: one section from up to two zeros and poles, right-aligned.
fn single_zpksos(z: &[C], p: &[C]) -> Sos {
    let mut s = [0.0; 6];
    let b = poly(z);
    let a = poly(p);
    s[3 - b.len()..3].copy_from_slice(&b);
    s[6 - a.len()..6].copy_from_slice(&a);
    Sos {
        b: [s[0], s[1], s[2]],
        a: [s[3], s[4], s[5]],
    }
}

/// scipy's `zpk2sos(z, p, k, pairing='nearest')` for a digital filter.
fn zpk2sos_nearest(z: Vec<C>, p: Vec<C>, k: f64) -> Vec<Sos> {
    let mut z = z;
    let mut p = p;
    let len = z.len().max(p.len());
    z.resize(len, C::real(0.0));
    p.resize(len, C::real(0.0));
    let n_sections = len.div_ceil(2);
    if p.len() % 2 == 1 {
        p.push(C::real(0.0));
        z.push(C::real(0.0));
    }
    let mut z = cplxreal(z);
    let mut p = cplxreal(p);
    let mut sos = vec![
        Sos {
            b: [0.0; 3],
            a: [0.0; 3]
        };
        n_sections
    ];
    for si in (0..n_sections).rev() {
        let p1 = p.remove(idx_worst(&p));
        let n_real_p = p.iter().filter(|c| c.is_real()).count();
        let n_real_z = z.iter().filter(|c| c.is_real()).count();
        if p1.is_real() && n_real_p == 0 {
            // The last remaining real pole: pair it with the nearest real zero, plus origin.
            let z1 = z.remove(nearest_idx(&z, p1, Which::Real));
            sos[si] = single_zpksos(&[z1, C::real(0.0)], &[p1, C::real(0.0)]);
        } else if p.len() + 1 == z.len() && !p1.is_real() && n_real_p == 1 && n_real_z == 1 {
            // One real pole and one real zero left: this complex pole must take complex zeros.
            let z1 = z.remove(nearest_idx(&z, p1, Which::Complex));
            sos[si] = single_zpksos(&[z1, z1.conj()], &[p1, p1.conj()]);
        } else {
            let p2 = if p1.is_real() {
                let real_idx: Vec<usize> = (0..p.len()).filter(|&i| p[i].is_real()).collect();
                let reals: Vec<C> = real_idx.iter().map(|&i| p[i]).collect();
                p.remove(real_idx[idx_worst(&reals)])
            } else {
                p1.conj()
            };
            if z.is_empty() {
                sos[si] = single_zpksos(&[], &[p1, p2]);
            } else {
                let z1 = z.remove(nearest_idx(&z, p1, Which::Any));
                if !z1.is_real() {
                    sos[si] = single_zpksos(&[z1, z1.conj()], &[p1, p2]);
                } else if z.is_empty() {
                    sos[si] = single_zpksos(&[z1], &[p1, p2]);
                } else {
                    let z2 = z.remove(nearest_idx(&z, p1, Which::Real));
                    sos[si] = single_zpksos(&[z1, z2], &[p1, p2]);
                }
            }
        }
    }
    for b in &mut sos[0].b {
        *b *= k;
    }
    sos
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bandpass_has_unit_gain_at_centre() {
        // |H| at the geometric centre of a Butterworth band-pass is 1.
        let (lo, hi, fs) = (10.0, 450.0, 1000.0);
        let sos = butter_bandpass(4, lo, hi, fs);
        assert_eq!(sos.len(), 4);
        let fc = {
            let w = |f: f64| (PI * f / fs).tan();
            (w(lo) * w(hi)).sqrt().atan() * fs / PI
        };
        let w = 2.0 * PI * fc / fs;
        let zi = C::new(w.cos(), -w.sin());
        let zi2 = zi.mul(zi);
        let mut h = C::real(1.0);
        for s in &sos {
            let num = C::real(s.b[0]).add(zi.scale(s.b[1])).add(zi2.scale(s.b[2]));
            let den = C::real(1.0).add(zi.scale(s.a[1])).add(zi2.scale(s.a[2]));
            h = h.mul(num.div(den));
        }
        assert!((h.abs() - 1.0).abs() < 1e-9, "|H(fc)| = {}", h.abs());
    }

    #[test]
    fn notch_zero_is_on_the_unit_circle_at_f0() {
        let s = iirnotch(50.0, 30.0, 1000.0);
        // b = g [1, -2 cos w0, 1]: zeros at exp(+-j w0), so H(e^{j w0}) = 0.
        let w = 2.0 * PI * 50.0 / 1000.0;
        let zi = C::new(w.cos(), -w.sin());
        let num = C::real(s.b[0])
            .add(zi.scale(s.b[1]))
            .add(zi.mul(zi).scale(s.b[2]));
        assert!(num.abs() < 1e-12);
    }
}
