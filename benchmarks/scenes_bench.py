"""Benchmark scenes and timing helpers shared by the benchmark scripts."""

import os
import platform
import time

import numpy as np

import exactff as ef


def machine():
    """One line: the machine and the versions the figures were measured with."""
    import shapely

    return (f"machine: {platform.machine()}, {os.cpu_count()} cores, python "
            f"{platform.python_version()}, numpy {np.__version__}, shapely "
            f"{shapely.__version__} (GEOS {shapely.geos_version_string})")


def timed(f):
    """``(f(), wall time in seconds)``."""
    t = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t


def best_of(f, k=3):
    """Best wall time of ``k`` calls of ``f`` (the machines are shared and noisy)."""
    ts = []
    for _ in range(k):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return min(ts)

#: an 8 x 6 x 2.8 m room (z up) with 6 desks, 3 partitions and 2 bookshelves as boxes;
#: the shelves stand against the wall y = 6 (their back faces lie in the wall's plane)
OFFICE_BOXES = [
    ((1.0, 1.0, 0.0), (2.6, 1.8, 0.75)), ((3.2, 1.0, 0.0), (4.8, 1.8, 0.75)),
    ((5.4, 1.0, 0.0), (7.0, 1.8, 0.75)), ((1.0, 3.6, 0.0), (2.6, 4.4, 0.75)),
    ((3.2, 3.6, 0.0), (4.8, 4.4, 0.75)), ((5.4, 3.6, 0.0), (7.0, 4.4, 0.75)),
    ((1.0, 2.6, 0.0), (2.8, 2.65, 1.5)), ((3.1, 2.6, 0.0), (4.9, 2.65, 1.5)),
    ((5.2, 2.6, 0.0), (7.0, 2.65, 1.5)),
    ((0.5, 5.6, 0.0), (2.5, 6.0, 2.0)), ((5.0, 5.6, 0.0), (7.0, 6.0, 2.0)),
]


def furnished_room(k=26, box_k=2, shelf_gap=0.0):
    """About 4,300 polygons for k = 26: 6 k^2 room quads plus 66 box_k^2 furniture quads.

    ``shelf_gap`` moves the shelves off the wall (1e-9 makes their back faces stiff
    horizon slivers for points on that wall)."""
    boxes = [(lo, (hi[0], hi[1] - shelf_gap, hi[2])) if hi[1] == 6.0 else (lo, hi)
             for lo, hi in OFFICE_BOXES]
    return ef.scenes.furnished_box(k, boxes, size=(8.0, 6.0, 2.8), box_k=box_k)
