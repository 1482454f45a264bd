#!/usr/bin/env python3
"""Samples this machine's steal time (jiffies in /proc/stat: the hypervisor under this machine
running something else) every PERIOD seconds until killed, one line per sample to stdout: host
time and the steal count. scripts/vm/run keeps it beside each boot, so a failing drill can be
set against the host's own stalls.

It never talks to qemu. Until stop 40 it asked qemu's monitor for `info jit` every 2 s, and
that query stopped the whole guest for 46-95 ms each time: the drills' EMG silences came every
2.06-2.09 s, each about 0.85 s (the guest clock's offset) after a query, and the hand stopped
on them (`invalid_window`) in the deploy, clock-step, subscribers and five-drive drills.

    steal_sampler.py [PERIOD]
"""
import sys
import time


def steal():
    try:
        with open("/proc/stat") as f:
            return int(f.readline().split()[8])
    except (OSError, IndexError, ValueError):
        return -1


def main():
    period = float(sys.argv[1]) if len(sys.argv) > 1 else 2.0
    while True:
        print(f"{time.time():.1f} steal {steal()}", flush=True)
        time.sleep(period)


if __name__ == "__main__":
    main()
