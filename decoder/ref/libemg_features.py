"""LibEMG-compatible features in plain numpy (issue 15): the reference the features-only path
(decoder::dsp::multichannel_features_into) is tested against, and the window set both sides of
the LibEMG benchmark run on.

LibEMG 2.0.3's definitions (libemg/feature_extractor.py, windows shaped (n, channels, samples),
every feature over the last axis):
  RMS   = sqrt(mean(x^2))
  MAV   = mean(|x|)
  VAR   = np.var(x)            (divides by N, ddof=0; ours divides by N - 1)
  IAV   = sum(|x|)             (our INT)
  WL    = sum(|diff(x)|)
  DASDV = sqrt(mean(diff(x)^2)) (the mean over the N - 1 differences, as ours)

Usage:
  libemg_features.py reference OUT_DIR DATA_DIR   windows.npy + libemg_features.npy (n, 6, ch)
                                                  from the real 3DC recording, raw and |x|
  libemg_features.py windows OUT.npy [N]          N seeded EMG-like 12 x 200 windows (bench)
"""
import sys
from pathlib import Path

import numpy as np

NAMES = ["RMS", "MAV", "VAR", "IAV", "WL", "DASDV"]
WINDOW = 200


def libemg_features(w):
    """(n, ch, N) windows -> (n, 6, ch), LibEMG's formulas in NAMES order."""
    d = np.diff(w, axis=2)
    return np.stack([
        np.sqrt(np.mean(np.square(w), 2)),
        np.mean(np.abs(w), 2),
        np.var(w, axis=2),
        np.sum(np.abs(w), axis=2),
        np.sum(np.abs(d), 2),
        np.sqrt(np.mean(d ** 2, axis=2)),
    ], axis=1)


def reference(out_dir, data_dir):
    emg = np.load(data_dir / "P4_train_emg.npy")  # (samples, 10) raw ADC-scale values
    starts = np.arange(0, min(len(emg) - WINDOW, 200_000), 4_001)[:40]
    w = np.stack([emg[s:s + WINDOW].T for s in starts])  # (n, ch, N)
    w = np.concatenate([w - w.mean(axis=2, keepdims=True), np.abs(w)])  # centred and rectified
    w = np.ascontiguousarray(w, dtype=np.float64)
    out_dir.mkdir(parents=True, exist_ok=True)
    np.save(out_dir / "windows.npy", w)
    np.save(out_dir / "libemg_features.npy", libemg_features(w))


def bench_windows(path, n):
    rng = np.random.default_rng(15)
    w = np.abs(rng.normal(0.0, 50.0, size=(n, 12, WINDOW)))
    np.save(path, np.ascontiguousarray(w))


if __name__ == "__main__":
    if sys.argv[1] == "reference":
        reference(Path(sys.argv[2]), Path(sys.argv[3]))
    elif sys.argv[1] == "windows":
        bench_windows(sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 1000)
    else:
        sys.exit(__doc__)
