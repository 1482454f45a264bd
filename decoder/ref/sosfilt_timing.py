#!/usr/bin/env python3
"""Times scipy.signal.sosfilt on the chain's default cascade (DC high-pass, 4th-order 10-450 Hz
band-pass, 50 Hz notch: 6 sections) over 60 s of 12-channel signal at 1 kHz, in process CPU
time, for comparison with the `chain/filter_60s_12ch_cpu` criterion benchmark.

Usage: sosfilt_timing.py [repeats]
"""
import sys
import time

import numpy as np
import scipy
from scipy import signal

fs = 1000.0
dc = signal.butter(1, 1.0, "highpass", fs=fs, output="sos")
bp = signal.butter(4, [10.0, 450.0], "bandpass", fs=fs, output="sos")
b, a = signal.iirnotch(50.0, 30.0, fs=fs)
cascade = np.vstack([dc, bp, np.concatenate([b, a])[None, :]])
assert cascade.shape == (6, 6)

rng = np.random.default_rng(0)
# Row-major (time, channel) like the recordings; sosfilt along axis 0.
x = rng.normal(0.0, 100.0, size=(60_000, 12))
xt = np.ascontiguousarray(x.T)  # (channel, time): sosfilt's fastest layout

repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 20
for name, data, axis in (("axis 0 (time, channel)", x, 0), ("axis -1 (channel, time)", xt, -1)):
    signal.sosfilt(cascade, data, axis=axis)  # warm up
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        signal.sosfilt(cascade, data, axis=axis)
        times.append(time.process_time() - t0)
    print(f"scipy {scipy.__version__} sosfilt, 6 sections, 60 s x 12 ch, {name}: "
          f"median {np.median(times) * 1e3:.2f} ms CPU ({repeats} runs)")
