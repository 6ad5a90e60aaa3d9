"""The peak resident memory of a child process, measured by the child itself.

``resource.getrusage(RUSAGE_SELF).ru_maxrss`` is no good here: Linux carries
the high-water mark across ``exec``, so a child started by a large test
process reports at least its parent's size. ``VmHWM`` in ``/proc/self/status``
belongs to the process's own address space and starts afresh at ``exec``.
"""

PEAK_KB = (
    "int(next(line.split()[1] for line in open('/proc/self/status') if line.startswith('VmHWM:')))"
)
"""A Python expression: the calling process's peak resident set size, kB (Linux)."""
