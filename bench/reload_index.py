#!/usr/bin/python3
"""Evict files from the page cache and read them back sequentially, so that the kernel caches
them as it caches a file read from disk rather than one just written. On Linux 6.x with ext4 or
XFS, read-ahead then fills the cache with large folios (up to 2 MB) that a memory mapping maps
with huge pages; pages left by the writer stay 4 KB. At 10M views a kd-forest search is a chain
of random reads over the index, and the huge pages save most of their TLB misses
(docs/benchmarks.md, "Latency"). The benchmarks run this on an index before timing it.

    bench/reload_index.py FILE [FILE ...]
"""
import os
import sys

for path in sys.argv[1:]:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)  # dirty pages cannot be dropped
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
        while os.read(fd, 1 << 24):
            pass
    finally:
        os.close(fd)
