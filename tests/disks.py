"""Filesystems that fill up, for the tests of what happens when a disk is full."""

import os


def fill(directory, free=0):
    """Write a file in ``directory`` until its filesystem has about ``free``
    bytes left (to within a page), or none at all."""
    path = os.path.join(directory, f"filler{len(os.listdir(directory))}")
    with open(path, "wb", buffering=0) as f:
        if free:
            stat = os.statvfs(directory)
            f.write(bytes(stat.f_bavail * stat.f_frsize - free))
            return
        for size in (4096, 1):
            try:
                while True:
                    f.write(bytes(size))
            except OSError:
                pass
