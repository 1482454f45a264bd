"""Independent numpy check of `handctl decode`'s agreement figures.

usage: decode_reference.py DECODE_CSV SOURCE_CSV REFERENCE_COLUMN RATE_HZ WINDOW_LEN FINGER

Reads the CSV `handctl decode` wrote (time_s, five outputs, reference) and the original samples
CSV with its reference column; resamples the reference to the windows itself (mean over the
WINDOW_LEN samples ending at each window's newest sample, found from time_s), and prints JSON:
the resampled reference's largest relative difference from decode's column, and for FINGER's
output against it: R² as is, RMSE as is, Pearson r, and R² / RMSE / slope / intercept of the
least-squares line reference = slope * output + intercept (numpy.polyfit).
"""
import json
import sys

import numpy as np

dec_path, src_path, ref_name, rate, wl, finger = sys.argv[1:7]
rate, wl = float(rate), int(wl)
dec = np.genfromtxt(dec_path, delimiter=",", names=True)
src = np.genfromtxt(src_path, delimiter=",", names=True)
ref_all = src[ref_name.lower()]
end = np.rint(dec["time_s"] * rate).astype(int) + 1
ref = np.array([ref_all[e - wl:e].mean() for e in end])
col = dec[ref_name.lower()]
ref_diff = float(np.max(np.abs(col - ref) / np.maximum(np.abs(ref), 1e-300)))
out = dec[finger]
ss_tot = np.sum((ref - ref.mean()) ** 2)
r2 = 1.0 - np.sum((ref - out) ** 2) / ss_tot
rmse = np.sqrt(np.mean((ref - out) ** 2))
r = np.corrcoef(out, ref)[0, 1]
slope, intercept = np.polyfit(out, ref, 1)
line = slope * out + intercept
r2_line = 1.0 - np.sum((ref - line) ** 2) / ss_tot
rmse_line = np.sqrt(np.mean((ref - line) ** 2))
print(json.dumps({
    "windows": int(len(out)),
    "reference_max_rel_diff": ref_diff,
    "r2": float(r2),
    "rmse": float(rmse),
    "pearson_r": float(r),
    "r2_line": float(r2_line),
    "rmse_line": float(rmse_line),
    "slope": float(slope),
    "intercept": float(intercept),
}))
