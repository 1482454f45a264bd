//! The paper's CNN baseline: 2 convolutions + 1 max-pool + 2 dense layers, ReLU after both
//! convolutions and the first dense layer, no output activation.
//!
//! The input (channel-major, `features_per_channel` values per electrode) is read as a sequence
//! over the **electrode axis** with the features as input channels: neighbouring electrodes on
//! an armband see overlapping muscles, so that is the axis where local weight sharing makes
//! sense (the 8 features of one electrode are different statistics, not a spatial sequence).
//! Convolutions use "same" zero padding (odd kernel); the max-pool has size 2, stride 2 over
//! electrodes (an odd last electrode is dropped by the pool, as in PyTorch's `MaxPool1d(2)`).
//! All layers have biases (PyTorch's default), so zero input does not give exactly zero output.
//! Initialisation: He-uniform before each ReLU, Glorot for the output layer, biases zero.

use super::batch::BatchWork;
use super::error::{check_params, ModelError};
use super::init::SeededRng;
use super::kind::ModelKind;
use super::linalg::{axpy, dot, matvec_bias, matvec_t, outer_acc, relu, relu_backward};
use super::spec::{check_width, CnnSpec};
use super::traits::{check_io, stacked, Model, Scratch, TensorInfo, Trainable};

/// The CNN baseline (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Cnn {
    spec: CnnSpec,
    n_in: usize,
    n_out: usize,
    params: Vec<f64>,
}

/// Shapes derived from a spec and the input size.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Dims {
    /// Electrodes (sequence length).
    pub(crate) p: usize,
    /// Features per electrode (input channels).
    pub(crate) cin: usize,
    pub(crate) f1: usize,
    pub(crate) f2: usize,
    pub(crate) k: usize,
    /// Pooled length.
    pub(crate) p2: usize,
    pub(crate) d: usize,
    pub(crate) n_out: usize,
}

impl Dims {
    pub(crate) fn sizes(&self) -> [usize; 8] {
        [
            self.f1 * self.k * self.cin,
            self.f1,
            self.f2 * self.k * self.f1,
            self.f2,
            self.d * self.p2 * self.f2,
            self.d,
            self.n_out * self.d,
            self.n_out,
        ]
    }
}

fn conv_forward(
    w: &[f64],
    b: &[f64],
    input: &[f64],
    cin: usize,
    cout: usize,
    k: usize,
    out: &mut [f64],
) {
    let p_len = input.len() / cin;
    let pad = k / 2;
    for p in 0..p_len {
        for o in 0..cout {
            let mut acc = b[o];
            for t in 0..k {
                let q = p + t;
                if q < pad || q - pad >= p_len {
                    continue;
                }
                let q = q - pad;
                acc += dot(
                    &w[(o * k + t) * cin..(o * k + t + 1) * cin],
                    &input[q * cin..(q + 1) * cin],
                );
            }
            out[p * cout + o] = acc;
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn conv_backward(
    w: &[f64],
    input: &[f64],
    cin: usize,
    cout: usize,
    k: usize,
    dout: &[f64],
    gw: &mut [f64],
    gb: &mut [f64],
    mut din: Option<&mut [f64]>,
) {
    let p_len = input.len() / cin;
    let pad = k / 2;
    if let Some(d) = din.as_deref_mut() {
        d.fill(0.0);
    }
    for p in 0..p_len {
        for o in 0..cout {
            let d = dout[p * cout + o];
            gb[o] += d;
            for t in 0..k {
                let q = p + t;
                if q < pad || q - pad >= p_len {
                    continue;
                }
                let q = q - pad;
                let wi = (o * k + t) * cin;
                axpy(d, &input[q * cin..(q + 1) * cin], &mut gw[wi..wi + cin]);
                if let Some(di) = din.as_deref_mut() {
                    axpy(d, &w[wi..wi + cin], &mut di[q * cin..(q + 1) * cin]);
                }
            }
        }
    }
}

impl Cnn {
    fn dims(spec: &CnnSpec, n_in: usize, n_out: usize) -> Result<Dims, ModelError> {
        check_width("CNN features per channel", spec.features_per_channel)?;
        check_width("CNN first conv filters", spec.filters[0])?;
        check_width("CNN second conv filters", spec.filters[1])?;
        check_width("CNN dense width", spec.dense)?;
        check_width("CNN input size", n_in)?;
        check_width("CNN output size", n_out)?;
        if spec.kernel.is_multiple_of(2) || spec.kernel > 15 {
            return Err(ModelError::InvalidSpec(format!(
                "CNN kernel must be odd and at most 15, got {}",
                spec.kernel
            )));
        }
        if !n_in.is_multiple_of(spec.features_per_channel) {
            return Err(ModelError::InvalidSpec(format!(
                "CNN input size {n_in} is not a multiple of {} features per channel",
                spec.features_per_channel
            )));
        }
        let p = n_in / spec.features_per_channel;
        if p < 2 {
            return Err(ModelError::InvalidSpec(format!(
                "CNN needs at least 2 electrodes for its max-pool, got {p}"
            )));
        }
        Ok(Dims {
            p,
            cin: spec.features_per_channel,
            f1: spec.filters[0],
            f2: spec.filters[1],
            k: spec.kernel,
            p2: p / 2,
            d: spec.dense,
            n_out,
        })
    }

    pub(crate) fn d(&self) -> Dims {
        Self::dims(&self.spec, self.n_in, self.n_out).expect("validated at construction")
    }

    /// Number of parameters for a shape.
    pub fn param_count(spec: &CnnSpec, n_in: usize, n_out: usize) -> Result<usize, ModelError> {
        Ok(Self::dims(spec, n_in, n_out)?.sizes().iter().sum())
    }

    /// Builds from parameters `[conv1.w (f1,k,cin), conv1.b, conv2.w (f2,k,f1), conv2.b,
    /// dense1.w (d, p/2·f2), dense1.b, dense2.w (n_out,d), dense2.b]`.
    pub fn from_params(
        spec: CnnSpec,
        n_in: usize,
        n_out: usize,
        params: Vec<f64>,
    ) -> Result<Self, ModelError> {
        let expected = Self::param_count(&spec, n_in, n_out)?;
        check_params("CNN", expected, &params)?;
        Ok(Cnn {
            spec,
            n_in,
            n_out,
            params,
        })
    }

    /// A randomly initialised CNN.
    pub fn random(spec: CnnSpec, n_in: usize, n_out: usize, seed: u64) -> Result<Self, ModelError> {
        Self::init(spec, n_in, n_out, &mut SeededRng::new(seed))
    }

    pub(crate) fn init(
        spec: CnnSpec,
        n_in: usize,
        n_out: usize,
        rng: &mut SeededRng,
    ) -> Result<Self, ModelError> {
        let dm = Self::dims(&spec, n_in, n_out)?;
        let sizes = dm.sizes();
        let mut params = vec![0.0; sizes.iter().sum()];
        let mut off = 0;
        let fan_in = [dm.cin * dm.k, 0, dm.f1 * dm.k, 0, dm.p2 * dm.f2, 0, dm.d, 0];
        for (i, &n) in sizes.iter().enumerate() {
            let w = &mut params[off..off + n];
            match i {
                0 | 2 | 4 => rng.he(w, fan_in[i]),
                6 => rng.xavier(w, dm.d, dm.n_out, 1.0),
                _ => {} // biases start at zero
            }
            off += n;
        }
        Ok(Cnn {
            spec,
            n_in,
            n_out,
            params,
        })
    }

    /// The tensors of a CNN of this shape, without building one. Errors on an invalid spec.
    pub fn layout(
        spec: &CnnSpec,
        n_in: usize,
        n_out: usize,
    ) -> Result<Vec<TensorInfo>, ModelError> {
        let dm = Self::dims(spec, n_in, n_out)?;
        let named = [
            ("conv1.weight", vec![dm.f1, dm.k, dm.cin]),
            ("conv1.bias", vec![dm.f1]),
            ("conv2.weight", vec![dm.f2, dm.k, dm.f1]),
            ("conv2.bias", vec![dm.f2]),
            ("dense1.weight", vec![dm.d, dm.p2 * dm.f2]),
            ("dense1.bias", vec![dm.d]),
            ("dense2.weight", vec![dm.n_out, dm.d]),
            ("dense2.bias", vec![dm.n_out]),
        ];
        Ok(stacked(
            named.into_iter().map(|(n, s)| (n.to_string(), s)).collect(),
        ))
    }

    /// The hyper-parameters.
    pub fn spec(&self) -> &CnnSpec {
        &self.spec
    }

    pub(crate) fn split(&self) -> [&[f64]; 8] {
        let sizes = self.d().sizes();
        let mut out: [&[f64]; 8] = [&[]; 8];
        let mut rest = &self.params[..];
        for (o, n) in out.iter_mut().zip(sizes) {
            let (a, b) = rest.split_at(n);
            *o = a;
            rest = b;
        }
        out
    }
}

impl Model for Cnn {
    fn kind(&self) -> ModelKind {
        ModelKind::Cnn
    }
    fn n_inputs(&self) -> usize {
        self.n_in
    }
    fn n_outputs(&self) -> usize {
        self.n_out
    }
    fn scratch_size(&self) -> (usize, usize) {
        let d = self.d();
        (
            2 * (d.p * d.f1 + d.p * d.f2 + d.p2 * d.f2 + d.d),
            d.p2 * d.f2,
        )
    }

    fn predict_with(&self, x: &[f64], y: &mut [f64], scratch: &mut Scratch) {
        check_io(self, x, y.len());
        let (nf, ni) = self.scratch_size();
        scratch.ensure(nf, ni);
        let dm = self.d();
        let [w1, b1, w2, b2, wd1, bd1, wd2, bd2] = self.split();
        let (c1, rest) = scratch.buf.split_at_mut(dm.p * dm.f1);
        let (c2, rest) = rest.split_at_mut(dm.p * dm.f2);
        let (pooled, rest) = rest.split_at_mut(dm.p2 * dm.f2);
        let hid = &mut rest[..dm.d];
        conv_forward(w1, b1, x, dm.cin, dm.f1, dm.k, c1);
        relu(c1);
        conv_forward(w2, b2, c1, dm.f1, dm.f2, dm.k, c2);
        relu(c2);
        for pp in 0..dm.p2 {
            for c in 0..dm.f2 {
                let (a, b) = (c2[2 * pp * dm.f2 + c], c2[(2 * pp + 1) * dm.f2 + c]);
                // Ties go to the first element, as in PyTorch.
                let (v, src) = if b > a { (b, 2 * pp + 1) } else { (a, 2 * pp) };
                pooled[pp * dm.f2 + c] = v;
                scratch.idx[pp * dm.f2 + c] = src;
            }
        }
        matvec_bias(wd1, bd1, pooled, hid);
        relu(hid);
        matvec_bias(wd2, bd2, hid, y);
    }
}

impl Trainable for Cnn {
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
        assert_eq!(grad.len(), self.params.len(), "CNN gradient length");
        let dm = self.d();
        let [w1, _, w2, _, wd1, _, wd2, _] = self.split();
        let sizes = dm.sizes();
        let mut g: [&mut [f64]; 8] = Default::default();
        let mut rest = grad;
        for (slot, n) in g.iter_mut().zip(sizes) {
            let (a, b) = rest.split_at_mut(n);
            *slot = a;
            rest = b;
        }
        let [gw1, gb1, gw2, gb2, gwd1, gbd1, gwd2, gbd2] = g;
        let (fwd, back) = scratch
            .buf
            .split_at_mut(dm.p * dm.f1 + dm.p * dm.f2 + dm.p2 * dm.f2 + dm.d);
        let (c1, rest) = fwd.split_at(dm.p * dm.f1);
        let (c2, rest) = rest.split_at(dm.p * dm.f2);
        let (pooled, hid) = rest.split_at(dm.p2 * dm.f2);
        let (d_hid, rest) = back.split_at_mut(dm.d);
        let (d_pool, rest) = rest.split_at_mut(dm.p2 * dm.f2);
        let (d_c2, rest) = rest.split_at_mut(dm.p * dm.f2);
        let d_c1 = &mut rest[..dm.p * dm.f1];

        outer_acc(gwd2, dy, hid);
        axpy(1.0, dy, gbd2);
        matvec_t(wd2, dy, d_hid);
        relu_backward(hid, d_hid);
        outer_acc(gwd1, d_hid, pooled);
        axpy(1.0, d_hid, gbd1);
        matvec_t(wd1, d_hid, d_pool);
        d_c2.fill(0.0);
        for (i, &dv) in d_pool.iter().enumerate() {
            let c = i % dm.f2;
            d_c2[scratch.idx[i] * dm.f2 + c] += dv;
        }
        relu_backward(c2, d_c2);
        conv_backward(w2, c1, dm.f1, dm.f2, dm.k, d_c2, gw2, gb2, Some(d_c1));
        relu_backward(c1, d_c1);
        conv_backward(w1, x, dm.cin, dm.f1, dm.k, d_c1, gw1, gb1, None);
    }

    fn batch_work_size(&self, rows: usize) -> (usize, usize) {
        self.batch_size(rows)
    }
    fn forward_batch(&self, x: &[f64], y: &mut [f64], work: &mut BatchWork) {
        self.forward_rows(x, y, work);
    }
    fn backward_batch(&self, x: &[f64], dy: &[f64], work: &mut BatchWork, grad: &mut [f64]) {
        self.backward_rows(x, dy, work, grad);
    }
}
