#!/usr/bin/env python3
# A bot that reads back the marks of send.py in a later match: it times a one-byte read of
# page k*STRIDE for each of N bits (readahead off) and writes on stderr `BITS <hex>` (bit k
# is 1 when the read took less than THRESHOLD microseconds: the page was cached) and the
# median times of the fast and slow reads. Then it ends.
import os
import sys
import time

path, n, stride, threshold_us = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
fd = os.open(path, os.O_RDONLY)
os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_RANDOM)
times = []
for k in range(n):
    t0 = time.perf_counter_ns()
    os.pread(fd, 1, k * stride * 4096)
    times.append((time.perf_counter_ns() - t0) / 1000)
value = 0
for k, t in enumerate(times):
    if t < threshold_us:
        value |= 1 << k
fast = sorted(t for t in times if t < threshold_us)
slow = sorted(t for t in times if t >= threshold_us)
median = lambda xs: xs[len(xs) // 2] if xs else -1
sys.stderr.write("BITS %x\n" % value)
sys.stderr.write("MEDIAN_US fast %.1f slow %.1f\n" % (median(fast), median(slow)))
sys.stdin.readline()
