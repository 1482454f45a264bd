"""The PyTorch peer of `cargo run --release -p decoder --example train_bench`: CPU time per
training epoch of ResDD (H=96, L=2), written as a PyTorch user would.

The same data bit for bit (SplitMix64 seed 7: 11 trials x 100 windows x 96 features, as
`decoder/examples/train_bench.rs`), the same trial-tail split (20% of each trial held out, 3
overlapping windows dropped: 847 train + 220 val windows), per-feature RMS scaling fitted on the
training windows, the same bias-free input-gated ResDD with the same initialisation scheme,
Adam (lr 1e-3), batch 32, masked MSE, a validation pass per epoch, a fixed number of epochs.
One thread (`torch.set_num_threads(1)`), float64; thread CPU time (`time.thread_time`).

Run: `python decoder/ref/train_torch.py [--json] [--epochs N] [--repeats R]` (PyTorch CPU in a
bench venv, never in the test command). `--json` prints one line
`{"what":"train_resdd_epoch","impl":"pytorch","ms_cpu_per_epoch":X,"epochs":N}`.
"""

import argparse
import json
import math
import time

import numpy as np
import torch
from torch import nn

MASK64 = (1 << 64) - 1


class SplitMix64:
    def __init__(self, seed):
        self.s = seed

    def unit(self):
        self.s = (self.s + 0x9E3779B97F4A7C15) & MASK64
        z = self.s
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK64
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK64
        z ^= z >> 31
        return (z >> 11) / float(1 << 53)


def calibration(windows=100, nf=96):
    """Features, targets, masks and trial ids, as `calibration` in train_bench.rs."""
    g = SplitMix64(7)
    mix = [[g.unit() ** 2 for _ in range(nf)] for _ in range(10)]
    xs, ts, ms, trials = [], [], [], []
    for trial in range(11):
        finger, sign = trial // 2, (1.0 if trial % 2 == 0 else -1.0)
        for _ in range(windows):
            x = [0.05 * g.unit() for _ in range(nf)]
            t, m = [0.0] * 5, [True] * 5
            if trial < 10:
                a = 0.8 + 0.2 * g.unit()
                src = mix[2 * finger + (1 if sign < 0 else 0)]
                x = [xi + a * s for xi, s in zip(x, src)]
                m = [False] * 5
                m[finger] = True
                t[finger] = sign
            xs.append([v * 50.0 for v in x])
            ts.append(t)
            ms.append(m)
            trials.append(trial)
    return np.array(xs), np.array(ts), np.array(ms, dtype=np.float64), np.array(trials)


def trial_tail_split(trials, fraction=0.2, gap=3):
    train, val = [], []
    for t in np.unique(trials):
        idx = np.flatnonzero(trials == t)
        n_val = round(fraction * len(idx))
        train.extend(idx[: len(idx) - n_val - gap])
        val.extend(idx[len(idx) - n_val :])
    return np.array(train), np.array(val)


class ResDD(nn.Module):
    """X = W_in x; A_l = G_l * X + G_l with G_l = W_l A_{l-1}; y = W_out A_L (no biases)."""

    def __init__(self, n_in=96, hidden=96, modules=2, n_out=5):
        super().__init__()
        self.w_in = nn.Linear(n_in, hidden, bias=False)
        self.mods = nn.ModuleList(nn.Linear(hidden, hidden, bias=False) for _ in range(modules))
        self.w_out = nn.Linear(hidden, n_out, bias=False)
        nn.init.xavier_uniform_(self.w_in.weight, gain=0.25)
        for m in self.mods:
            nn.init.xavier_uniform_(m.weight)
        nn.init.xavier_uniform_(self.w_out.weight)

    def forward(self, x):
        xh = self.w_in(x)
        a = xh
        for m in self.mods:
            g = m(a)
            a = g * xh + g
        return self.w_out(a)


def masked_mse(y, t, m):
    return ((y - t) ** 2 * m).sum() / m.sum()


def train(x, t, m, train_idx, val_idx, epochs, seed=0):
    torch.manual_seed(seed)
    model = ResDD().double()
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    xtr, ttr, mtr = x[train_idx], t[train_idx], m[train_idx]
    xva, tva, mva = x[val_idx], t[val_idx], m[val_idx]
    n = len(train_idx)
    for _ in range(epochs):
        model.train()
        perm = torch.randperm(n)
        for b in range(0, n, 32):
            i = perm[b : b + 32]
            opt.zero_grad()
            loss = masked_mse(model(xtr[i]), ttr[i], mtr[i])
            loss.backward()
            opt.step()
        model.eval()
        with torch.no_grad():
            val = masked_mse(model(xva), tva, mva).item()
    return loss.item(), val


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--epochs", type=int, default=83)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    torch.set_num_threads(1)
    x, t, m, trials = calibration()
    train_idx, val_idx = trial_tail_split(trials)
    scale = 1.0 / np.sqrt((x[train_idx] ** 2).mean(axis=0))
    x, t, m = (torch.from_numpy(v) for v in (x * scale, t, m))
    per_epoch = []
    for r in range(a.repeats + 1):  # the first run warms up
        start = time.thread_time()
        loss, val = train(x, t, m, train_idx, val_idx, a.epochs, seed=r)
        per_epoch.append((time.thread_time() - start) * 1e3 / a.epochs)
    runs = sorted(per_epoch[1:])
    median = runs[len(runs) // 2]
    if a.json:
        print(json.dumps({"what": "train_resdd_epoch", "impl": "pytorch",
                          "ms_cpu_per_epoch": round(median, 4), "epochs": a.epochs},
                         separators=(",", ":")))
    else:
        print(f"PyTorch {torch.__version__} ResDD H=96 L=2, {len(train_idx)} train + "
              f"{len(val_idx)} val windows x 96 features, batch 32, Adam, {a.epochs} epochs, "
              f"{torch.get_num_threads()} thread")
        print(f"CPU ms per epoch: median {median:.3f} of {len(runs)} runs "
              f"(all: {[round(v, 3) for v in runs]}); final train loss {loss:.5f}, val {val:.5f}")
        assert math.isfinite(loss)


if __name__ == "__main__":
    main()
