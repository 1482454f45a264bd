"""What the ADS1299's sinc3 decimation filter costs the features, 1 kSPS vs 2 kSPS + an FIR
decimator to 1 kHz on the node (firmware/amp-node/README.md, "Data rate").

The sinc3 filter's magnitude is |sin(pi f N / fMOD) / (N sin(pi f / fMOD))|^3 with
N = fMOD / fDR (fMOD = 1.024 MHz): -3 dB at 0.262 fDR. Applied here as a zero-phase magnitude
weighting in the frequency domain to each 1 kHz 3DC recording (its phase is a pure delay, which
amplitude features do not see). The recordings are already sampled at 1 kHz, so the aliasing
that 1 kSPS would let through from above 500 Hz cannot be measured from them: only the
in-band droop is. Features (paper Table 1: RMS, MAV, WL, DASDV; VAR, SD, INT and DAMV follow
RMS, MAV and DASDV) over 200-sample windows stepped by 50 after the chain's band-pass
(Butterworth order 4, 10-450 Hz, causal SOS; no notch: no mains line in these recordings),
each recording filtered on its own. Prints the relative feature change against the
unweighted recording (median and 95th percentile over windows x channels, all 3 participants,
train split).

Usage: .venv/bin/python firmware/amp-node/ref/sinc_cost.py [../shared/data]
"""

import csv
import sys
from pathlib import Path

import numpy as np
from scipy import signal

F_MOD = 1.024e6
FS = 1000.0


def sinc3(f, f_dr):
    n = F_MOD / f_dr
    x = np.pi * f / F_MOD
    with np.errstate(invalid="ignore", divide="ignore"):
        h = np.where(f == 0, 1.0, np.sin(n * x) / (n * np.sin(x)))
    return np.abs(h) ** 3


def decimator_response(f):
    # A 2 kHz -> 1 kHz decimating FIR the node could run: 63 taps, Kaiser window, cutoff
    # 475 Hz (about 60 dB attenuation from 550 Hz on, what aliases into 450..500 Hz).
    taps = signal.firwin(63, 475.0, fs=2000.0, window=("kaiser", 6.0))
    _, h = signal.freqz(taps, worN=f, fs=2000.0)
    return np.abs(h)


def features(x):
    # x: (n, ch) band-passed; windows of 200 stepped by 50.
    out = []
    for s in range(0, x.shape[0] - 200 + 1, 50):
        w = x[s : s + 200]
        d = np.diff(w, axis=0)
        out.append(
            np.stack(
                [
                    np.sqrt(np.mean(w**2, axis=0)),  # RMS
                    np.mean(np.abs(w), axis=0),  # MAV
                    np.sum(np.abs(d), axis=0),  # WL
                    np.sqrt(np.mean(d**2, axis=0)),  # DASDV
                ]
            )
        )
    return np.array(out)  # (windows, 4, ch)


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else "../shared/data")
    sos = signal.butter(4, [10.0, 450.0], btype="bandpass", fs=FS, output="sos")
    variants = {}
    for p in (4, 6, 7):
        d = root / f"3dc-armband-p{p}"
        emg = np.load(d / f"P{p}_train_emg.npy").astype(float)
        with open(d / f"P{p}_train_index.csv") as fh:
            rows = list(csv.DictReader(fh))
        for r in rows:
            x = emg[int(r["start_sample"]) : int(r["end_sample_exclusive"])]
            n = x.shape[0]
            f = np.fft.rfftfreq(n, 1.0 / FS)
            spec = np.fft.rfft(x, axis=0)
            h1 = sinc3(f, 1000.0)
            h2 = sinc3(f, 2000.0) * decimator_response(f)
            ref = features(signal.sosfilt(sos, x, axis=0))
            for name, h in (("1 kSPS", h1), ("2 kSPS + FIR", h2)):
                y = np.fft.irfft(spec * h[:, None], n=n, axis=0)
                fy = features(signal.sosfilt(sos, y, axis=0))
                rel = (fy - ref) / np.where(ref == 0, np.nan, ref)
                variants.setdefault(name, []).append(rel)
    names = ["RMS", "MAV", "WL", "DASDV"]
    print("relative feature change vs the unweighted recording (median / 95th pct of |change|)")
    for name, rels in variants.items():
        rel = np.concatenate(rels, axis=0)
        cells = []
        for k, fname in enumerate(names):
            a = np.abs(rel[:, k, :])
            a = a[np.isfinite(a)]
            cells.append(f"{fname} {100 * np.median(a):.1f}% / {100 * np.percentile(a, 95):.1f}%")
        print(f"{name:>13}: " + ", ".join(cells))
    f = np.array([100.0, 200.0, 262.0, 300.0, 400.0, 450.0])
    print("gain at", ", ".join(f"{int(v)}" for v in f), "Hz:")
    print("  1 kSPS       ", " ".join(f"{20 * np.log10(v):6.2f}" for v in sinc3(f, 1000.0)), "dB")
    h2 = sinc3(f, 2000.0) * decimator_response(f)
    print("  2 kSPS + FIR ", " ".join(f"{20 * np.log10(v):6.2f}" for v in h2), "dB")


if __name__ == "__main__":
    main()
