#!/usr/bin/env python3
"""Independent reference for decoder::dsp, written with scipy and plain numpy.

Usage: chain_reference.py OUT_DIR DATA_DIR

Writes into OUT_DIR:
  manifest.json      the configurations, the designed sections, and the list of recordings
  filtered_K.npy     float64 (n, 10): recording K filtered by scipy.signal.sosfilt with scipy's
                     own designed sections: DC high-pass, band-pass, notch (one cascade)
  features_K.npy     float64 (rows, 80): the paper's Table 1 features of |filtered|, numpy
  features_unrect_K.npy  the same features of the unrectified filtered signal

The chain under test (Rust) designs its own sections and runs its own filter; this script only
uses scipy's design functions and sosfilt, so the comparison checks both.
"""
import json
import sys
from pathlib import Path

import numpy as np
import scipy
from scipy import signal

# The chain's stages (must match decoder::dsp's documented design):
#   DC removal: butter(1, dc_cutoff, 'highpass', fs=fs, output='sos')
#   band-pass:  butter(order, [lo, hi], 'bandpass', fs=fs, output='sos')
#   notch:      iirnotch(mains * h, Q, fs=fs) for h = 1..1+harmonics, as one section each
DESIGNS = [
    dict(sample_rate_hz=1000.0, band_low_hz=10.0, band_high_hz=450.0, bandpass_order=4,
         mains_hz=50, notch_q=30.0, mains_harmonics=0, dc_cutoff_hz=1.0),
    dict(sample_rate_hz=2000.0, band_low_hz=20.0, band_high_hz=500.0, bandpass_order=2,
         mains_hz=60, notch_q=30.0, mains_harmonics=2, dc_cutoff_hz=2.0),
    dict(sample_rate_hz=200.0, band_low_hz=10.0, band_high_hz=90.0, bandpass_order=4,
         mains_hz=50, notch_q=25.0, mains_harmonics=0, dc_cutoff_hz=0.5),
    dict(sample_rate_hz=1000.0, band_low_hz=20.0, band_high_hz=400.0, bandpass_order=3,
         mains_hz=60, notch_q=35.0, mains_harmonics=1, dc_cutoff_hz=1.0),
    dict(sample_rate_hz=1500.0, band_low_hz=5.0, band_high_hz=700.0, bandpass_order=6,
         mains_hz=50, notch_q=10.0, mains_harmonics=3, dc_cutoff_hz=0.3),
]

# The chain configuration used on the real recordings (10 channels, otherwise the defaults).
CHAIN = dict(channels=10, window_ms=200.0, step_ms=50.0, **DESIGNS[0])

# Recordings compared: both files, gestures 0 (neutral), 2, 7 (power grip), 8 (open hand),
# repetitions 0 and 3.
GESTURES = (0, 2, 7, 8)
REPS = (0, 3)


def design(cfg):
    fs = cfg["sample_rate_hz"]
    dc = signal.butter(1, cfg["dc_cutoff_hz"], "highpass", fs=fs, output="sos")
    bp = signal.butter(cfg["bandpass_order"], [cfg["band_low_hz"], cfg["band_high_hz"]],
                       "bandpass", fs=fs, output="sos")
    notches = []
    for h in range(1, cfg["mains_harmonics"] + 2):
        b, a = signal.iirnotch(cfg["mains_hz"] * h, cfg["notch_q"], fs=fs)
        notches.append(np.concatenate([b, a]))
    return dc, bp, np.array(notches)


def features(x, window, step):
    """Table 1 of the paper over every window x[end-window:end], end = window + i*step."""
    n, ch = x.shape
    if n < window:
        return np.zeros((0, 8 * ch))
    ends = np.arange(window, n + 1, step)
    out = np.empty((len(ends), ch, 8))
    for r, end in enumerate(ends):
        w = x[end - window:end]
        d = np.diff(w, axis=0)
        N = window
        out[r, :, 0] = np.sqrt(np.mean(w ** 2, axis=0))
        out[r, :, 1] = np.mean(np.abs(w), axis=0)
        out[r, :, 2] = np.sum((w - w.mean(axis=0)) ** 2, axis=0) / (N - 1)
        out[r, :, 3] = np.sqrt(out[r, :, 2])
        out[r, :, 4] = np.sum(np.abs(w), axis=0)
        out[r, :, 5] = np.sum(np.abs(d), axis=0)
        out[r, :, 6] = np.sqrt(np.sum(d ** 2, axis=0) / (N - 1))
        out[r, :, 7] = np.sum(np.abs(d), axis=0) / (N - 1)
    return out.reshape(len(ends), ch * 8)  # channel-major


def main():
    out_dir, data_dir = Path(sys.argv[1]), Path(sys.argv[2])
    out_dir.mkdir(parents=True, exist_ok=True)

    designs = []
    for cfg in DESIGNS:
        dc, bp, notch = design(cfg)
        designs.append(dict(config=cfg, dc=dc.tolist(), bandpass=bp.tolist(), notch=notch.tolist()))

    fs = CHAIN["sample_rate_hz"]
    window = int(round(CHAIN["window_ms"] * fs / 1000))
    step = int(round(CHAIN["step_ms"] * fs / 1000))
    dc, bp, notch = design(CHAIN)
    cascade = np.vstack([dc, bp, notch])

    recordings = []
    for split in ("train", "test"):
        emg = np.load(data_dir / f"P4_{split}_emg.npy")
        index = np.genfromtxt(data_dir / f"P4_{split}_index.csv", delimiter=",", names=True,
                              dtype=None, encoding="utf-8", usecols=(0, 1, 3, 4))
        for row in index:
            rep, gesture, start, end = (int(row[k]) for k in index.dtype.names)
            if gesture not in GESTURES or rep not in REPS:
                continue
            k = len(recordings)
            x = emg[start:end].astype(np.float64)
            y = np.ascontiguousarray(signal.sosfilt(cascade, x, axis=0))  # from zero state
            np.save(out_dir / f"filtered_{k}.npy", y)
            np.save(out_dir / f"features_{k}.npy", features(np.abs(y), window, step))
            np.save(out_dir / f"features_unrect_{k}.npy", features(y, window, step))
            recordings.append(dict(split=split, rep=rep, gesture=gesture, start=start, end=end, k=k))

    manifest = dict(scipy=scipy.__version__, numpy=np.__version__, designs=designs,
                    chain=CHAIN, window=window, step=step, recordings=recordings)
    (out_dir / "manifest.json").write_text(json.dumps(manifest, indent=1))
    print(f"chain_reference: {len(recordings)} recordings, {len(designs)} designs, "
          f"scipy {scipy.__version__} -> {out_dir}")


if __name__ == "__main__":
    main()
