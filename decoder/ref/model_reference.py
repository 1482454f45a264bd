#!/usr/bin/env python3
"""Independent numpy forward passes of the four decoder models (ResDD, LN, MLP, CNN).

Reads one JSON object on stdin:
  {"kind": "resdd"|"ln"|"mlp"|"cnn", "spec": {...ModelSpec block...},
   "tensors": [{"name", "shape", "offset"}], "params": [...], "inputs": [[...], ...]}
and prints {"outputs": [[...], ...]}.

Written from the architecture definitions (the issue and DESIGN.md section 4), in the
conventions of PyTorch where there is one: the CNN uses Conv1d layout (batch, channels, length)
with the electrode axis as length and the 8 features as input channels, weights
(out, in, kernel), zero "same" padding, MaxPool1d(2). The Rust model stores conv weights as
(out, kernel, in) and flattens the pooled map position-major; this file converts explicitly, so
a layout mistake on either side shows up as a mismatch.
"""
import json
import sys

import numpy as np


def tensors(req):
    p = np.asarray(req["params"], dtype=np.float64)
    out = {}
    for t in req["tensors"]:
        n = int(np.prod(t["shape"]))
        out[t["name"]] = p[t["offset"]:t["offset"] + n].reshape(t["shape"])
    return out


def resdd(req, T, x):
    spec = req["spec"]
    X = T["w_in"] @ x
    A = X
    for l in range(1, spec["modules"] + 1):
        G = T[f"w_mod.{l}"] @ A
        M = X if spec["variant"] == "input_gated" else A
        A = G * M + G
    return T["w_out"] @ A


def ln(req, T, x):
    return T["w3"] @ (T["w2"] @ (T["w1"] @ x))


def mlp(req, T, x):
    relu = lambda v: np.maximum(v, 0.0)
    h1 = relu(T["w1"] @ x + T["b1.bias"])
    h2 = relu(T["w2"] @ h1 + T["b2.bias"])
    return T["w3"] @ h2 + T["b3.bias"]


def conv1d_same(inp, w, b):
    """inp (cin, P); w (cout, cin, k) PyTorch layout; zero padding k//2 each side."""
    cin, P = inp.shape
    cout, _, k = w.shape
    pad = k // 2
    padded = np.zeros((cin, P + 2 * pad))
    padded[:, pad:pad + P] = inp
    out = np.empty((cout, P))
    for p in range(P):
        out[:, p] = np.einsum("oik,ik->o", w, padded[:, p:p + k]) + b
    return out


def cnn(req, T, x):
    spec = req["spec"]
    fpc = spec["features_per_channel"]
    P = x.size // fpc
    inp = x.reshape(P, fpc).T  # (features as channels, electrodes as length)
    relu = lambda v: np.maximum(v, 0.0)
    w1 = T["conv1.weight"].transpose(0, 2, 1)  # (out, k, in) -> (out, in, k)
    w2 = T["conv2.weight"].transpose(0, 2, 1)
    c1 = relu(conv1d_same(inp, w1, T["conv1.bias"]))
    c2 = relu(conv1d_same(c1, w2, T["conv2.bias"]))
    P2 = P // 2
    pooled = c2[:, :2 * P2].reshape(c2.shape[0], P2, 2).max(axis=2)  # MaxPool1d(2)
    flat = pooled.T.reshape(-1)  # position-major, as the Rust model stores dense1's columns
    h = relu(T["dense1.weight"] @ flat + T["dense1.bias"])
    return T["dense2.weight"] @ h + T["dense2.bias"]


def main():
    req = json.load(sys.stdin)
    T = tensors(req)
    f = {"resdd": resdd, "ln": ln, "mlp": mlp, "cnn": cnn}[req["kind"]]
    outs = [f(req, T, np.asarray(x, dtype=np.float64)).tolist() for x in req["inputs"]]
    json.dump({"outputs": outs}, sys.stdout)


if __name__ == "__main__":
    main()
