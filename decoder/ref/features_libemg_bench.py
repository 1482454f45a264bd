"""LibEMG's FeatureExtractor on the six features it shares with handstack (issue 15), timed in
this process's CPU time on the windows of WINDOWS.npy ((n, 12, 200), from
`libemg_features.py windows`). Prints three JSON lines: one window per call (as online) over
all the windows (`online`) and over the first 8 cycled, in cache (`online_hot`), and one call
for all windows (`batched`), each in microseconds of CPU per window. Needs LibEMG (the bench
venv of scripts/bench), never the test's .venv.

  features_libemg_bench.py WINDOWS.npy
"""
import json
import sys
import time

import numpy as np
from libemg.feature_extractor import FeatureExtractor

from libemg_features import NAMES, libemg_features


# Distinct windows of the `online_hot` measurement (handstack's features_bench uses the same).
HOT = 8


def cpu_per_call(f, calls, rounds=7):
    """Median over rounds of the process CPU time per call of f, in microseconds."""
    times = []
    for _ in range(rounds):
        t0 = time.process_time()
        for _ in range(calls):
            f()
        times.append((time.process_time() - t0) / calls * 1e6)
    return float(np.median(times))


def main():
    w = np.load(sys.argv[1])
    fe = FeatureExtractor()
    got = fe.extract_features(NAMES, w)
    want = libemg_features(w)
    for i, name in enumerate(NAMES):  # the reference reproduces LibEMG here too
        assert np.allclose(got[name], want[:, i, :], rtol=1e-12, atol=0), name
    one = [w[i:i + 1] for i in range(len(w))]
    it = iter(range(10**9))
    online = cpu_per_call(lambda: fe.extract_features(NAMES, one[next(it) % len(one)]), 200)
    # The first HOT windows cycled: the window in cache, as handstack's features_bench `hot`.
    hot = one[:HOT]
    online_hot = cpu_per_call(lambda: fe.extract_features(NAMES, hot[next(it) % len(hot)]), 200)
    batched = cpu_per_call(lambda: fe.extract_features(NAMES, w), 3) / len(w)
    for mode, us in (("online", online), ("online_hot", online_hot), ("batched", batched)):
        print(json.dumps(dict(what="features_window", impl="libemg", mode=mode,
                              us_cpu_per_window=round(us, 3), windows=HOT if mode == "online_hot" else len(w),
                              channels=w.shape[1], samples=w.shape[2])))


if __name__ == "__main__":
    main()
