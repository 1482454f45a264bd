//! Optimizer state and update steps over a flat parameter vector.

use super::config::Optimizer;

/// Per-parameter state of an optimizer.
pub(crate) struct OptimState {
    rule: Optimizer,
    m: Vec<f64>,
    v: Vec<f64>,
    t: i32,
}

impl OptimState {
    pub(crate) fn new(rule: Optimizer, n: usize) -> Self {
        let v = match rule {
            Optimizer::Adam { .. } => vec![0.0; n],
            Optimizer::Sgd { .. } => Vec::new(),
        };
        OptimState {
            rule,
            m: vec![0.0; n],
            v,
            t: 0,
        }
    }

    /// One update of `params` from the (already averaged) gradient `grad`.
    pub(crate) fn step(&mut self, params: &mut [f64], grad: &[f64]) {
        match self.rule {
            Optimizer::Adam {
                lr,
                beta1,
                beta2,
                eps,
            } => {
                self.t = self.t.saturating_add(1);
                let c1 = 1.0 - beta1.powi(self.t);
                let c2 = 1.0 - beta2.powi(self.t);
                let step = lr / c1;
                // `sqrt(v) / sqrt(c2)` as a product: one division per parameter fewer (the
                // step's cost is its divisions and square roots).
                let inv_c2_sqrt = 1.0 / c2.sqrt();
                for (((p, g), m), v) in params
                    .iter_mut()
                    .zip(grad)
                    .zip(&mut self.m)
                    .zip(&mut self.v)
                {
                    *m = beta1 * *m + (1.0 - beta1) * g;
                    *v = beta2 * *v + (1.0 - beta2) * g * g;
                    *p -= step * *m / (v.sqrt() * inv_c2_sqrt + eps);
                }
            }
            Optimizer::Sgd { lr, momentum } => {
                for ((p, g), m) in params.iter_mut().zip(grad).zip(&mut self.m) {
                    *m = momentum * *m + g;
                    *p -= lr * *m;
                }
            }
        }
    }
}
