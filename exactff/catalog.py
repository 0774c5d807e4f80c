"""The catalogue of stiff cases, with 60-digit references (``tools/make_stiff_catalog.py``).

Each case is a receiver (point, normal) and one polygon, given as exact float input,
with the reference form factor from mpmath at 80 digits (quadrature of the image's
boundary integral, cross-checked against the closed-form sector sum), kept to 60.
"""

import json
from importlib import resources
from typing import NamedTuple

import numpy as np

__all__ = ["StiffCase", "stiff_cases"]


class StiffCase(NamedTuple):
    """One catalogue entry; ``reference`` is a 60-digit decimal string. ``one_sided`` is
    the data file's field (whether only the polygon's front receives); read it as
    :attr:`two_sided`, the options' name."""

    name: str
    point: np.ndarray
    normal: np.ndarray
    polygon: np.ndarray
    one_sided: bool
    reference: str
    double_rel_error_when_generated: float

    @property
    def two_sided(self):
        """Whether the polygon's back receives too: the ``two_sided=`` to pass."""
        return not self.one_sided


def stiff_cases():
    """The stiff cases: tiny, horizon slivers, adjacent walls, zenith edges, far away,
    huge, nearly coplanar, short-and-long edges, needles, many-vertex discs.

    Returns
    -------
    list of StiffCase

    Examples
    --------
    >>> cases = stiff_cases()
    >>> len(cases) >= 25, cases[0].name
    (True, 'tiny_square_1e-03')
    """
    text = resources.files("exactff").joinpath("data/stiff_cases.json").read_text("utf-8")
    out = []
    for c in json.loads(text)["cases"]:
        out.append(StiffCase(
            c["name"],
            np.array([float(v) for v in c["point"]]),
            np.array([float(v) for v in c["normal"]]),
            np.array([[float(v) for v in row] for row in c["polygon"]]),
            bool(c["one_sided"]),
            c["reference"],
            float(c["double_rel_error_when_generated"]),
        ))
    return out
