#!/usr/bin/env python3
# A bot that marks pages of a large file of /usr in the host's page cache: page k*STRIDE is
# read for each bit k that is 1 (readahead off). Then it plays nothing and ends. Used by
# benches/page_cache.sh to measure what a read-latency probe still carries between matches.
import os
import sys

path, bits, stride = sys.argv[1], sys.argv[2], int(sys.argv[3])
fd = os.open(path, os.O_RDONLY)
os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_RANDOM)
for k, b in enumerate(bits):
    if b == "1":
        os.pread(fd, 1, k * stride * 4096)
sys.stdin.readline()
