"""A method that records, per row, the process, the scene object it was given and
whether that scene already held the BSP tree of the engine that computes the row (the
compiled core's, or the Python engine's); importable by worker processes."""

import os
import time

from exactff.methods import Exact
from exactff.prepared import prepared


class RecordingExact(Exact):
    """The exact method, logging ``pid id(scene) had_bsp row`` lines to ``log``."""

    def __init__(self, log):
        super().__init__()
        self.log = log

    def point_form_factors(self, scene, point, normal, two_sided=False, **kw):
        # a run to be killed part-way takes this long a row at least (seconds,
        # EXACTFF_TEST_ROW_DELAY in its environment), so that the kill falls mid-run
        # however fast the rows are
        time.sleep(float(os.environ.get("EXACTFF_TEST_ROW_DELAY", "0")))
        # the accelerator each engine builds once per scene: the compiled core (its BSP
        # tree and subtree bounds) or the Python engine's BSP tree and buckets
        had = ("compiled_core" if self.engine == "compiled" else "bsp") in prepared(scene)
        F = super().point_form_factors(scene, point, normal, two_sided=two_sided, **kw)
        with open(self.log, "a", encoding="utf-8") as fh:
            fh.write(f"{os.getpid()} {id(scene)} {int(had)} {point.tolist()}\n")
        return F


def read_log(path):
    with open(path, encoding="utf-8") as fh:
        return [line.split(" ", 3) for line in fh]
