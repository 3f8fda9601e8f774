"""Peak memory of a measured process, for the perf scripts that start one per case."""

from __future__ import annotations

#: Python source that defines ``peak_mib()`` in a measured process: its peak resident
#: memory in MiB, read from ``VmHWM``, which unlike ``ru_maxrss`` leaves out the memory of
#: the parent it was forked from.  Source, not a function, so that it also runs in another
#: checkout measured with ``--code``.
PEAK_MIB = """
def peak_mib():
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmHWM:")) // 1024
"""
