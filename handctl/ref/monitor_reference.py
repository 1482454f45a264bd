"""Independent reference for `handctl monitor --log`: from the candump text alone, with cantools
(hand.dbc) and scipy, what the screen must show at the end of the log.

- per channel: the RMS (uV) of the band-passed signal over the last 200 samples, the chain
  built from scipy: butter(1, 1 Hz, highpass), butter(4, [10, 450] Hz, bandpass),
  iirnotch(50 Hz, Q 30), run with sosfilt over every complete sample of the log;
- per finger: the label of the last HAND_DIAG frame.

usage: monitor_reference.py LOG DBC  -> prints JSON {"rms_uv": [...], "labels": [...]}
"""
import json
import sys

import cantools
import numpy as np
from scipy import signal

FS = 1000.0
CHANNELS = 12


def frames(path):
    with open(path) as f:
        for line in f:
            parts = line.split()
            if len(parts) != 3:
                continue
            cid, data = parts[2].split("#")
            yield int(cid, 16), bytes.fromhex(data)


def main():
    log, dbc = sys.argv[1], sys.argv[2]
    db = cantools.database.load_file(dbc)
    groups = {db.get_message_by_name(f"EMG_SAMPLES_G{g}").frame_id: g for g in range(3)}
    diag = db.get_message_by_name("HAND_DIAG")
    samples, pending, labels = [], {}, None
    for cid, data in frames(log):
        if cid in groups:
            g = groups[cid]
            m = db.decode_message(cid, data, decode_choices=False)
            counter = m["Counter"]
            if g == 0:
                pending = {"counter": counter}
            if pending.get("counter") != counter:
                raise SystemExit(f"sample with counter {counter} out of order")
            for k in range(4):
                pending[4 * g + k] = m[f"Emg{4 * g + k}"]
            if g == 2:
                samples.append([pending[c] for c in range(CHANNELS)])
                pending = {}
        elif cid == diag.frame_id:
            m = db.decode_message(cid, data)
            labels = [m[f"Label{f}"] for f in range(5)]
    x = np.asarray(samples, dtype=float)
    sos = np.vstack([
        signal.butter(1, 1.0, "highpass", fs=FS, output="sos"),
        signal.butter(4, [10.0, 450.0], "bandpass", fs=FS, output="sos"),
        signal.tf2sos(*signal.iirnotch(50.0, 30.0, fs=FS)),
    ])
    y = signal.sosfilt(sos, x, axis=0)
    rms = np.sqrt(np.mean(y[-200:] ** 2, axis=0))
    print(json.dumps({"rms_uv": rms.tolist(), "labels": labels, "samples": len(samples)}))


if __name__ == "__main__":
    main()
