#!/usr/bin/env python3
"""Cross-check of hand.dbc and the Rust codec against cantools (the reference DBC codec).

Run by can-dbc/tests/cantools.rs; usable by hand:

    cantools_check.py --dbc can-dbc/hand.dbc --rust rust_vectors.json --out py_vectors.json

1. Loads hand.dbc in cantools strict mode; any warning (Python warnings or cantools log
   records at WARNING or above) is a failure.
2. For every Rust vector (message id, physical values, payload bytes produced by the Rust
   codec): cantools must encode the same values to the same bytes, and decode the Rust bytes
   to the same values. For E2E-protected messages, the CRC byte is recomputed here with an
   independent bitwise CRC-8 SAE J1850 over the data id and the payload. A vector that carries
   "info" (the generated MESSAGES entry: senders, receivers, cycle time, E2E data id, and
   per signal unit and value table) must match the message as cantools read it.
3. Writes its own vectors (random in-range values encoded by cantools) for the Rust side to
   decode and re-encode.

Exit status 0 only if every check passed; failures are listed on stderr.
"""

import argparse
import json
import logging
import math
import random
import sys
import warnings

import cantools


def crc8_j1850(data):
    """CRC-8 SAE J1850: poly 0x1D, init 0xFF, xorout 0xFF, bitwise (independent of Rust's table)."""
    crc = 0xFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


assert crc8_j1850(b"123456789") == 0x4B


class _Collect(logging.Handler):
    def __init__(self):
        super().__init__(level=logging.WARNING)
        self.records = []

    def emit(self, record):
        self.records.append(record.getMessage())


def load_strict(path):
    handler = _Collect()
    root = logging.getLogger()
    root.addHandler(handler)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            db = cantools.database.load_file(path, strict=True)
    finally:
        root.removeHandler(handler)
    problems = [f"warning: {w.message}" for w in caught] + [f"log: {r}" for r in handler.records]
    return db, problems


def raw_range(sig):
    """Raw integer range allowed by the signal's physical [min, max]."""
    lo = (sig.minimum - sig.offset) / sig.scale
    hi = (sig.maximum - sig.offset) / sig.scale
    return math.ceil(lo - 1e-9), math.floor(hi + 1e-9)


def is_integer_signal(sig):
    return sig.scale == 1 and sig.offset == 0


def close(a, b, sig):
    return abs(float(a) - float(b)) <= abs(sig.scale) * 1e-6 + 1e-9 * max(1.0, abs(float(a)))


def e2e_of(db, msg):
    attrs = msg.dbc.attributes if msg.dbc else {}
    data_id = attrs["HandE2EDataId"].value if "HandE2EDataId" in attrs else 0
    return data_id


def info_problems(db, msg, info):
    """Differences between the generated MESSAGES entry and the message as cantools read it."""
    out = []
    if sorted(info["senders"]) != sorted(msg.senders):
        out.append(f"{msg.name}: senders Rust {info['senders']} cantools {msg.senders}")
    receivers = sorted({r for sig in msg.signals for r in sig.receivers if r != "Vector__XXX"})
    if sorted(info["receivers"]) != receivers:
        out.append(f"{msg.name}: receivers Rust {info['receivers']} cantools {receivers}")
    if info["cycle_time_ms"] != (msg.cycle_time or 0):
        out.append(f"{msg.name}: cycle time Rust {info['cycle_time_ms']} cantools {msg.cycle_time}")
    if info["e2e_data_id"] != e2e_of(db, msg):
        out.append(f"{msg.name}: E2E data id Rust {info['e2e_data_id']:#06x} cantools {e2e_of(db, msg):#06x}")
    for sig in msg.signals:
        mine = info["signals"].get(sig.name)
        if mine is None:
            out.append(f"{msg.name}.{sig.name}: missing in Rust's MESSAGES")
            continue
        theirs = {str(int(k)): str(v) for k, v in (sig.choices or {}).items()}
        if mine["choices"] != theirs:
            out.append(f"{msg.name}.{sig.name}: value table Rust {mine['choices']} cantools {theirs}")
        if mine["unit"] != (sig.unit or ""):
            out.append(f"{msg.name}.{sig.name}: unit Rust {mine['unit']!r} cantools {sig.unit!r}")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dbc", required=True)
    ap.add_argument("--rust", required=True, help="vectors written by the Rust codec (JSON)")
    ap.add_argument("--out", required=True, help="where to write cantools' own vectors (JSON)")
    ap.add_argument("--n", type=int, default=1000, help="vectors per message to generate")
    ap.add_argument("--seed", type=int, default=20260522)
    args = ap.parse_args()

    failures = []
    db, problems = load_strict(args.dbc)
    failures += [f"hand.dbc does not load cleanly in cantools strict mode: {p}" for p in problems]

    with open(args.rust) as f:
        rust = json.load(f)

    # The Rust codec must know exactly the messages cantools knows.
    rust_ids = {v["id"] for v in rust}
    db_ids = {m.frame_id for m in db.messages}
    if rust_ids != db_ids:
        failures.append(f"message ids differ: only in Rust {sorted(rust_ids - db_ids)}, only in cantools {sorted(db_ids - rust_ids)}")

    counts = {}
    described = set()
    for vec in rust:
        try:
            msg = db.get_message_by_frame_id(vec["id"])
        except KeyError:
            continue
        counts[msg.name] = counts.get(msg.name, 0) + 1
        if "info" in vec:
            described.add(msg.name)
            failures += info_problems(db, msg, vec["info"])
        data = bytes.fromhex(vec["data"])
        values = vec["values"]
        names = {s.name for s in msg.signals}
        if set(values) != names:
            failures.append(f"{msg.name}: Rust signals {sorted(values)} != cantools {sorted(names)}")
            continue
        if len(data) != msg.length:
            failures.append(f"{msg.name}: Rust DLC {len(data)} != cantools {msg.length}")
            continue
        # Encode the Rust values with cantools: same bytes.
        try:
            ours = msg.encode(values, scaling=True, strict=True)
        except Exception as e:  # noqa: BLE001 - any refusal is a disagreement
            failures.append(f"{msg.name}: cantools refused Rust values {values}: {e}")
            continue
        if bytes(ours) != data:
            failures.append(f"{msg.name}: bytes differ for {values}: Rust {data.hex()} cantools {bytes(ours).hex()}")
        # Decode the Rust bytes with cantools: same values.
        decoded = msg.decode(data, decode_choices=False, scaling=True)
        for sig in msg.signals:
            if not close(decoded[sig.name], values[sig.name], sig):
                failures.append(f"{msg.name}.{sig.name}: cantools decodes {decoded[sig.name]}, Rust had {values[sig.name]} (bytes {data.hex()})")
        # E2E: the CRC the Rust protector wrote is the J1850 CRC over data id + payload.
        data_id = e2e_of(db, msg)
        if data_id:
            want = crc8_j1850(bytes([data_id & 0xFF, data_id >> 8]) + data[1:])
            if data[0] != want:
                failures.append(f"{msg.name}: CRC byte {data[0]:#04x} != J1850 over data id {data_id:#06x} + payload: {want:#04x}")
    for m in db.messages:
        if m.name not in described:
            failures.append(f"{m.name}: no Rust vector carried its MESSAGES entry")
        if counts.get(m.name, 0) < args.n:
            failures.append(f"{m.name}: only {counts.get(m.name, 0)} Rust vectors, need {args.n}")

    # cantools' own vectors for the Rust side.
    rng = random.Random(args.seed)
    out = []
    for msg in db.messages:
        for k in range(args.n):
            values = {}
            for sig in msg.signals:
                lo, hi = raw_range(sig)
                if sig.choices:
                    raw = rng.choice(sorted(int(c) for c in sig.choices))
                else:
                    # Hit both range ends explicitly, then uniform.
                    raw = lo if k == 0 else hi if k == 1 else rng.randint(lo, hi)
                values[sig.name] = raw if is_integer_signal(sig) else raw * sig.scale + sig.offset
            data = msg.encode(values, scaling=True, strict=True)
            out.append({"id": msg.frame_id, "name": msg.name, "values": values, "data": bytes(data).hex()})
    with open(args.out, "w") as f:
        json.dump(out, f)

    if failures:
        print(f"cantools_check: {len(failures)} failure(s):", file=sys.stderr)
        for line in failures[:40]:
            print("  " + line, file=sys.stderr)
        return 1
    print(f"cantools_check: cantools {cantools.__version__}: hand.dbc loads strict without warnings; "
          f"{len(rust)} Rust vectors agree bit for bit; wrote {len(out)} cantools vectors")
    return 0


if __name__ == "__main__":
    sys.exit(main())
