"""Independent reference for decoder::eval: AUC (Mann-Whitney U), Spearman rho, least squares.

Reads JSON {"cases": [{"scores": [...], "positive": [...], "x": [...], "y": [...]}, ...]} on
stdin and writes {"results": [{"auc": .., "spearman": .., "slope": .., "intercept": .., "r2": ..}]}
on stdout, computed with scipy and numpy only.
"""
import json
import sys

import numpy as np
from scipy import stats


def main():
    cases = json.load(sys.stdin)["cases"]
    out = []
    for c in cases:
        s = np.asarray(c["scores"], dtype=float)
        p = np.asarray(c["positive"], dtype=bool)
        u = stats.mannwhitneyu(s[p], s[~p], alternative="two-sided").statistic
        auc = float(u) / (p.sum() * (~p).sum())
        x = np.asarray(c["x"], dtype=float)
        y = np.asarray(c["y"], dtype=float)
        rho = float(stats.spearmanr(x, y).statistic)
        slope, intercept = np.polyfit(x, y, 1)
        pred = slope * x + intercept
        r2 = 1.0 - np.sum((y - pred) ** 2) / np.sum((y - y.mean()) ** 2)
        out.append({"auc": auc, "spearman": rho, "slope": float(slope),
                    "intercept": float(intercept), "r2": float(r2)})
    json.dump({"results": out}, sys.stdout)


if __name__ == "__main__":
    main()
