//! The effort-ray penalty of a whole mini-batch at once: every window's ray points go through
//! one batched forward pass and one batched backward pass (see [`super::effort`] for the
//! penalty itself; the result equals summing [`super::ray_penalty`] window by window, up to the
//! summation order of the matrix products).

use super::batch::BatchWork;
use super::dataset::N_FINGERS;
use super::effort::charge;
use super::traits::Trainable;
use crate::eval::scale_features;

/// The rays of one mini-batch: scaled inputs, outputs and their gradients, one row per point;
/// buffers sized once for the largest batch.
#[derive(Debug, Clone)]
pub(crate) struct RayBatch {
    n_in: usize,
    points: usize,
    rays: usize,
    x: Vec<f64>,
    y: Vec<[f64; N_FINGERS]>,
    dy: Vec<[f64; N_FINGERS]>,
    ks: Vec<f64>,
    dirs: Vec<[f64; N_FINGERS]>,
    /// The charged points only (inputs, outputs, scaled gradients), for the backward pass.
    charged_x: Vec<f64>,
    charged_y: Vec<f64>,
    charged_dy: Vec<f64>,
}

impl RayBatch {
    /// Room for `max_rays` rays of `points` efforts each (`points` = jittered points + 2).
    pub(crate) fn new(n_in: usize, points: usize, max_rays: usize) -> Self {
        let rows = points * max_rays;
        RayBatch {
            n_in,
            points,
            rays: 0,
            x: vec![0.0; rows * n_in],
            y: vec![[0.0; N_FINGERS]; rows],
            dy: vec![[0.0; N_FINGERS]; rows],
            ks: vec![0.0; rows],
            dirs: vec![[0.0; N_FINGERS]; max_rays],
            charged_x: vec![0.0; rows * n_in],
            charged_y: vec![0.0; rows * N_FINGERS],
            charged_dy: vec![0.0; rows * N_FINGERS],
        }
    }

    /// Most rays per batch.
    pub(crate) fn capacity(&self) -> usize {
        self.dirs.len()
    }

    /// Forgets the rays of the previous batch.
    pub(crate) fn clear(&mut self) {
        self.rays = 0;
    }

    /// Adds the ray of the window with normalized features `x`, finger directions `dirs` and
    /// efforts `ks` (`points` long, ascending). Panics past [`RayBatch::capacity`].
    pub(crate) fn push(&mut self, x: &[f64], dirs: &[f64; N_FINGERS], ks: &[f64]) {
        assert!(self.rays < self.capacity(), "ray batch full");
        assert_eq!(ks.len(), self.points, "one effort per ray point");
        let r0 = self.rays * self.points;
        for (j, &k) in ks.iter().enumerate() {
            let row = (r0 + j) * self.n_in;
            scale_features(x, k, &mut self.x[row..row + self.n_in]);
        }
        self.ks[r0..r0 + self.points].copy_from_slice(ks);
        self.dirs[self.rays] = *dirs;
        self.rays += 1;
    }

    /// The penalty of every ray added since [`RayBatch::clear`], summed ray by ray in order.
    /// With `grad`, adds `scale · ∂P/∂θ` to it. The model must have [`N_FINGERS`] outputs and
    /// `work` room for `capacity() · points` rows.
    pub(crate) fn run<M: Trainable + ?Sized>(
        &mut self,
        model: &M,
        min_slope: f64,
        work: &mut BatchWork,
        grad: Option<(&mut [f64], f64)>,
    ) -> f64 {
        assert_eq!(model.n_outputs(), N_FINGERS, "ray batch: five outputs");
        let rows = self.rays * self.points;
        if rows == 0 {
            return 0.0;
        }
        let x = &self.x[..rows * self.n_in];
        model.forward_batch(x, self.y[..rows].as_flattened_mut(), work);
        let mut penalty = 0.0;
        for (r, dirs) in self.dirs[..self.rays].iter().enumerate() {
            let pts = r * self.points..(r + 1) * self.points;
            self.dy[pts.clone()].fill([0.0; N_FINGERS]);
            let (y, ks) = (&self.y[pts.clone()], &self.ks[pts.clone()]);
            penalty += charge(y, &mut self.dy[pts], dirs, ks, min_slope);
        }
        if let Some((grad, scale)) = grad {
            self.backward_charged(model, rows, work, grad, scale);
        }
        penalty
    }

    /// Back-propagates `scale` times the output gradients of the points that have one (on a
    /// trained model most points are not charged): gathers them, reruns their forward pass for
    /// the activations, then one batched backward pass.
    fn backward_charged<M: Trainable + ?Sized>(
        &mut self,
        model: &M,
        rows: usize,
        work: &mut BatchWork,
        grad: &mut [f64],
        scale: f64,
    ) {
        let n_in = self.n_in;
        let mut n = 0;
        for (r, dy) in self.dy[..rows].iter().enumerate() {
            if dy.iter().all(|&d| d == 0.0) {
                continue;
            }
            let (src, dst) = (r * n_in..(r + 1) * n_in, n * n_in..(n + 1) * n_in);
            self.charged_x[dst].copy_from_slice(&self.x[src]);
            for (c, d) in self.charged_dy[n * N_FINGERS..(n + 1) * N_FINGERS]
                .iter_mut()
                .zip(dy)
            {
                *c = d * scale;
            }
            n += 1;
        }
        if n == 0 {
            return;
        }
        let x = &self.charged_x[..n * n_in];
        model.forward_batch(x, &mut self.charged_y[..n * N_FINGERS], work);
        model.backward_batch(x, &self.charged_dy[..n * N_FINGERS], work, grad);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{ray_penalty, AnyModel, Model, ModelKind, ModelSpec, RayWork};

    /// The batched penalty and gradient equal [`ray_penalty`] summed window by window.
    #[test]
    fn batch_equals_window_by_window() {
        let m = AnyModel::random(ModelKind::ResDd, &ModelSpec::default(), 96, 5, 4).unwrap();
        let ks = [0.0, 0.1, 0.45, 0.7, 1.0];
        let dirs = [[1.0, 0.0, -1.0, 0.0, 0.0], [0.0, -1.0, 0.0, 0.0, 1.0]];
        let xs: Vec<Vec<f64>> = (0..2)
            .map(|w| {
                (0..96)
                    .map(|i| ((i * 7 + w * 13) % 23) as f64 / 9.0)
                    .collect()
            })
            .collect();
        let (mut want_grad, mut want) = (vec![0.0; m.params().len()], 0.0);
        let (mut work, mut s) = (RayWork::new(96, ks.len()), m.new_scratch());
        for (x, d) in xs.iter().zip(&dirs) {
            let g = Some((&mut want_grad[..], 0.3));
            want += ray_penalty(&m, x, d, &ks, 1.0, &mut work, &mut s, g);
        }
        let mut rays = RayBatch::new(96, ks.len(), 4);
        let mut bw = m.new_batch_work(4 * ks.len());
        for (x, d) in xs.iter().zip(&dirs) {
            rays.push(x, d, &ks);
        }
        let mut grad = vec![0.0; m.params().len()];
        let got = rays.run(&m, 1.0, &mut bw, Some((&mut grad, 0.3)));
        assert!(
            want > 0.0 && (got - want).abs() <= 1e-12 * want,
            "{got} vs {want}"
        );
        let scale = want_grad.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (a, b) in grad.iter().zip(&want_grad) {
            assert!((a - b).abs() <= 1e-12 * scale, "{a} vs {b}");
        }
    }
}
