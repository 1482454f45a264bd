//! ResDD, the paper's near-linear decoder:
//! `X = W_in·x` (H x n_in), modules `G_l = W_l·A_{l-1}`, `A_l = G_l∘M_l + G_l` with `A_0 = X` and
//! `M_l = X` (input-gated, default) or `M_l = A_{l-1}` (chained), then `y = W_out·A_L`.
//!
//! Bias-free, so `x = 0` gives `y = 0` exactly. Each module is a linear map plus a
//! multiplicative term, so with small `X` the model is close to linear; initialisation keeps
//! `X` small (see [`ResDd::random`]) so training starts from a near-linear map.

use super::batch::BatchWork;
use super::error::{check_params, ModelError};
use super::init::SeededRng;
use super::kind::ModelKind;
use super::linalg::{matvec, matvec_t, outer_acc};
use super::spec::{check_width, ResDdSpec, ResDdVariant, MAX_MODULES};
use super::traits::{check_io, stacked, Model, Scratch, TensorInfo, Trainable};

/// Gain of `W_in`'s Glorot initialisation: with unit-RMS inputs `X` has RMS about 0.25, so the
/// quadratic term `G∘X` starts at about a quarter of the linear term `G`.
pub const RESDD_INPUT_GAIN: f64 = 0.25;

/// A ResDD network (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ResDd {
    spec: ResDdSpec,
    n_in: usize,
    n_out: usize,
    params: Vec<f64>,
}

impl ResDd {
    /// Number of parameters for a shape.
    pub fn param_count(spec: &ResDdSpec, n_in: usize, n_out: usize) -> usize {
        let h = spec.hidden;
        h * n_in + spec.modules * h * h + n_out * h
    }

    fn check(spec: &ResDdSpec, n_in: usize, n_out: usize) -> Result<(), ModelError> {
        check_width("ResDD hidden width", spec.hidden)?;
        check_width("ResDD input size", n_in)?;
        check_width("ResDD output size", n_out)?;
        if spec.modules > MAX_MODULES {
            return Err(ModelError::InvalidSpec(format!(
                "ResDD modules must be at most {MAX_MODULES}, got {}",
                spec.modules
            )));
        }
        Ok(())
    }

    /// Builds from an explicit parameter vector `[W_in, W_1 .. W_L, W_out]`, each row-major.
    pub fn from_params(
        spec: ResDdSpec,
        n_in: usize,
        n_out: usize,
        params: Vec<f64>,
    ) -> Result<Self, ModelError> {
        Self::check(&spec, n_in, n_out)?;
        let expected = Self::param_count(&spec, n_in, n_out);
        check_params("ResDD", expected, &params)?;
        Ok(ResDd {
            spec,
            n_in,
            n_out,
            params,
        })
    }

    /// Random initialisation from `seed`: Glorot-uniform for every matrix, with gain
    /// [`RESDD_INPUT_GAIN`] on `W_in` so the model starts near-linear.
    pub fn random(
        spec: ResDdSpec,
        n_in: usize,
        n_out: usize,
        seed: u64,
    ) -> Result<Self, ModelError> {
        Self::init(spec, n_in, n_out, &mut SeededRng::new(seed))
    }

    pub(crate) fn init(
        spec: ResDdSpec,
        n_in: usize,
        n_out: usize,
        rng: &mut SeededRng,
    ) -> Result<Self, ModelError> {
        Self::check(&spec, n_in, n_out)?;
        let h = spec.hidden;
        let mut params = vec![0.0; Self::param_count(&spec, n_in, n_out)];
        let (w_in, rest) = params.split_at_mut(h * n_in);
        rng.xavier(w_in, n_in, h, RESDD_INPUT_GAIN);
        let (w_mods, w_out) = rest.split_at_mut(spec.modules * h * h);
        for w in w_mods.chunks_exact_mut(h * h) {
            rng.xavier(w, h, h, 1.0);
        }
        rng.xavier(w_out, h, n_out, 1.0);
        Ok(ResDd {
            spec,
            n_in,
            n_out,
            params,
        })
    }

    /// The tensors of a ResDD of this shape (`w_in`, `w_mod.1`..`w_mod.L`, `w_out`), without
    /// building one. Errors on an invalid spec.
    pub fn layout(
        spec: &ResDdSpec,
        n_in: usize,
        n_out: usize,
    ) -> Result<Vec<TensorInfo>, ModelError> {
        Self::check(spec, n_in, n_out)?;
        let h = spec.hidden;
        let mut named = vec![("w_in".to_string(), vec![h, n_in])];
        named.extend((1..=spec.modules).map(|l| (format!("w_mod.{l}"), vec![h, h])));
        named.push(("w_out".to_string(), vec![n_out, h]));
        Ok(stacked(named))
    }

    /// The hyper-parameters.
    pub fn spec(&self) -> &ResDdSpec {
        &self.spec
    }

    /// The activations of the last [`Model::predict_with`] that used `scratch`: `X`, `G_l`
    /// and `A_l` (for inspection and tests).
    pub fn activations<'s>(&self, scratch: &'s Scratch) -> ResDdActivations<'s> {
        let h = self.spec.hidden;
        let l = self.spec.modules;
        assert!(
            scratch.buf.len() >= (1 + 2 * l) * h,
            "scratch too small for this ResDD"
        );
        ResDdActivations::over(h, l, &scratch.buf)
    }

    pub(crate) fn split_params(&self) -> (&[f64], &[f64], &[f64]) {
        let h = self.spec.hidden;
        let (w_in, rest) = self.params.split_at(h * self.n_in);
        let (w_mods, w_out) = rest.split_at(self.spec.modules * h * h);
        (w_in, w_mods, w_out)
    }
}

impl Model for ResDd {
    fn kind(&self) -> ModelKind {
        ModelKind::ResDd
    }
    fn n_inputs(&self) -> usize {
        self.n_in
    }
    fn n_outputs(&self) -> usize {
        self.n_out
    }
    fn scratch_size(&self) -> (usize, usize) {
        ((5 + 2 * self.spec.modules) * self.spec.hidden, 0)
    }

    fn predict_with(&self, x: &[f64], y: &mut [f64], scratch: &mut Scratch) {
        check_io(self, x, y.len());
        let (nf, ni) = self.scratch_size();
        scratch.ensure(nf, ni);
        let h = self.spec.hidden;
        let l_count = self.spec.modules;
        let (w_in, w_mods, w_out) = self.split_params();
        let (xh, rest) = scratch.buf.split_at_mut(h);
        let (g_all, rest) = rest.split_at_mut(l_count * h);
        let a_all = &mut rest[..l_count * h];
        matvec(w_in, x, xh);
        for l in 0..l_count {
            let w = &w_mods[l * h * h..(l + 1) * h * h];
            let g = &mut g_all[l * h..(l + 1) * h];
            let (before, after) = a_all.split_at_mut(l * h);
            let prev: &[f64] = if l == 0 { xh } else { &before[(l - 1) * h..] };
            let cur = &mut after[..h];
            matvec(w, prev, g);
            let gate: &[f64] = match self.spec.variant {
                ResDdVariant::InputGated => xh,
                ResDdVariant::Chained => prev,
            };
            for ((a, gi), mi) in cur.iter_mut().zip(g.iter()).zip(gate) {
                *a = gi * mi + gi;
            }
        }
        let last: &[f64] = if l_count == 0 {
            xh
        } else {
            &a_all[(l_count - 1) * h..]
        };
        matvec(w_out, last, y);
    }
}

impl Trainable for ResDd {
    fn params(&self) -> &[f64] {
        &self.params
    }
    fn params_mut(&mut self) -> &mut [f64] {
        &mut self.params
    }

    fn tensors(&self) -> Vec<TensorInfo> {
        Self::layout(&self.spec, self.n_in, self.n_out).expect("validated at construction")
    }

    fn backward(&self, x: &[f64], dy: &[f64], scratch: &mut Scratch, grad: &mut [f64]) {
        check_io(self, x, dy.len());
        assert_eq!(grad.len(), self.params.len(), "ResDD gradient length");
        let h = self.spec.hidden;
        let l_count = self.spec.modules;
        let (_, w_mods, w_out) = self.split_params();
        let (g_in, rest) = grad.split_at_mut(h * self.n_in);
        let (g_mods, g_out) = rest.split_at_mut(l_count * h * h);
        // Forward activations [X, G_1..G_L, A_1..A_L], then the backward buffers.
        let (fwd, back) = scratch.buf.split_at_mut(h + 2 * l_count * h);
        let act = ResDdActivations::over(h, l_count, fwd);
        let (a, rest) = back.split_at_mut(h);
        let (prev, rest) = rest.split_at_mut(h);
        let (g, rest) = rest.split_at_mut(h);
        let mut d = Deltas {
            a,
            prev,
            g,
            x: &mut rest[..h],
        };

        outer_acc(g_out, dy, act.a(l_count));
        matvec_t(w_out, dy, d.a);
        d.x.fill(0.0);
        for l in (1..=l_count).rev() {
            let m = (l - 1) * h * h..l * h * h;
            self.module_backward(&act, l, &w_mods[m.clone()], &mut g_mods[m], &mut d);
        }
        // A_0 = X.
        for (dx, da) in d.x.iter_mut().zip(d.a.iter()) {
            *dx += da;
        }
        outer_acc(g_in, d.x, x);
    }

    fn batch_work_size(&self, rows: usize) -> (usize, usize) {
        (self.batch_floats(rows), 0)
    }
    fn forward_batch(&self, x: &[f64], y: &mut [f64], work: &mut BatchWork) {
        self.forward_rows(x, y, work);
    }
    fn backward_batch(&self, x: &[f64], dy: &[f64], work: &mut BatchWork, grad: &mut [f64]) {
        self.backward_rows(x, dy, work, grad);
    }
}

/// The backward pass's work vectors, each `hidden` long.
struct Deltas<'s> {
    /// `dA_l` of the module being differentiated (on exit from a module: `dA_{l-1}`).
    a: &'s mut [f64],
    /// `dA_{l-1}` being built.
    prev: &'s mut [f64],
    /// `dG_l`.
    g: &'s mut [f64],
    /// `dX` collected so far.
    x: &'s mut [f64],
}

impl ResDd {
    /// Back through module `l` (weights `w`, their gradient `g_w`): from `dA_l` in `d.a`,
    /// accumulates `dW_l`, adds the gate's share to `dX` (input-gated) and leaves `dA_{l-1}` in
    /// `d.a`.
    fn module_backward(
        &self,
        act: &ResDdActivations<'_>,
        l: usize,
        w: &[f64],
        g_w: &mut [f64],
        d: &mut Deltas<'_>,
    ) {
        let g = act.g(l);
        let prev = act.a(l - 1);
        let gate = match self.spec.variant {
            ResDdVariant::InputGated => act.x(),
            ResDdVariant::Chained => prev,
        };
        // A = G∘(M + 1): dG = dA∘(M + 1), dM = dA∘G.
        for ((dg, da), m) in d.g.iter_mut().zip(d.a.iter()).zip(gate) {
            *dg = da * (m + 1.0);
        }
        outer_acc(g_w, d.g, prev);
        matvec_t(w, d.g, d.prev);
        let d_m: &mut [f64] = match self.spec.variant {
            ResDdVariant::InputGated => &mut *d.x,
            ResDdVariant::Chained => &mut *d.prev,
        };
        for ((dm, da), gi) in d_m.iter_mut().zip(d.a.iter()).zip(g) {
            *dm += da * gi;
        }
        d.a.copy_from_slice(d.prev);
    }
}

/// Borrowed view of a ResDD's hidden activations (see [`ResDd::activations`]).
#[derive(Debug, Clone, Copy)]
pub struct ResDdActivations<'s> {
    h: usize,
    x: &'s [f64],
    g: &'s [f64],
    a: &'s [f64],
}

impl<'s> ResDdActivations<'s> {
    /// The view of `buf` laid out as `[X, G_1..G_L, A_1..A_L]` for width `h` and `l` modules.
    fn over(h: usize, l: usize, buf: &'s [f64]) -> Self {
        ResDdActivations {
            h,
            x: &buf[..h],
            g: &buf[h..h + l * h],
            a: &buf[h + l * h..h + 2 * l * h],
        }
    }

    /// The projected input `X = W_in·x`.
    pub fn x(&self) -> &'s [f64] {
        self.x
    }
    /// `G_l` for module `l` in `1..=L`.
    pub fn g(&self, l: usize) -> &'s [f64] {
        &self.g[(l - 1) * self.h..l * self.h]
    }
    /// `A_l` for `l` in `0..=L` (`A_0 = X`).
    pub fn a(&self, l: usize) -> &'s [f64] {
        if l == 0 {
            self.x
        } else {
            &self.a[(l - 1) * self.h..l * self.h]
        }
    }
}
