#!/usr/bin/env python3
"""Samples qemu's translation-cache counters (`info jit` on its HMP monitor socket) every
PERIOD seconds until the socket goes away, one line per sample to stdout: host time, TB flush
count, TB count, and the host's own steal time (jiffies in /proc/stat, the hypervisor under
this machine running something else). A TB flush stops every vCPU while the cache is emptied, and everything run
after it is translated again: the guest-wide stalls the vcan drills' meters see may be these.

    jit_sampler.py SOCKET [PERIOD]
"""
import re
import socket
import sys
import time


def query(path):
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.settimeout(5)
    s.connect(path)
    buf = b""
    while b"(qemu)" not in buf:
        buf += s.recv(4096)
    s.sendall(b"info jit\n")
    buf = b""
    while buf.count(b"(qemu)") < 1:
        chunk = s.recv(65536)
        if not chunk:
            break
        buf += chunk
    s.close()
    return buf.decode(errors="replace")


def steal():
    try:
        with open("/proc/stat") as f:
            return int(f.readline().split()[8])
    except (OSError, IndexError, ValueError):
        return -1


def main():
    path = sys.argv[1]
    period = float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
    for _ in range(600):
        try:
            socket.socket(socket.AF_UNIX).connect(path)
            break
        except OSError:
            time.sleep(0.2)
    while True:
        try:
            text = query(path)
        except OSError:
            return
        flush = re.search(r"TB flush count\s+(\d+)", text)
        count = re.search(r"Translation buffer state:.*?TB count\s+(\d+)", text, re.S)
        print(
            f"{time.time():.1f} flushes {flush.group(1) if flush else '?'} "
            f"tbs {count.group(1) if count else '?'} steal {steal()}",
            flush=True,
        )
        time.sleep(period)


if __name__ == "__main__":
    main()
