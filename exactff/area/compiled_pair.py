"""An occluded pair's integral in one compiled call (``_core/occluded_pair.cpp``, module
:mod:`exactff.area._pair`, the GIL released): the steps of
:func:`exactff.area.adaptive._hidden_integral`, its reference, from the pair's frames to
its value, with numpy's roundings kept (np.sum's pairwise sums, the BLAS's products:
``_core/numpy_ops.h``) so that the values are the reference's to the bit; and the
tolerances and rules the compiled levels read.
"""

import itertools
import operator

import numpy as np

from .. import _tolerances as tol
from ..halfspace import NORMAL_FLOOR
from ._pair import occluded_pair as _compiled_occluded_pair
from ._pair import pair_constants as _compiled_pair_constants
from .rules import CORNER_MIDDLE_RULE, RULE_PAIRS, SYMMETRIC_NULL_RULES, SYMMETRIC_RULES

__all__ = ["LEVEL_RULES", "LEVEL_TOLERANCES", "PAIR_TOLERANCES", "blas_fuses",
           "hidden_integral_in_one_call", "pair_constants"]

#: The compiled levels' rules, in levels.h's order: the symmetric pair (degrees 4 and 8),
#: the collapsed pairs of rung 0 and rung 1, the third rule at a corner, and the small
#: triangles' pair on rung 0 (degrees 2 and 4), and the symmetric pair's two null rules
#: of degree 5 (weights on the 22 nodes of the degree-4 rule, then the degree-8 rule's).
LEVEL_RULES = (*(SYMMETRIC_RULES[d] for d in tol.AREA_SYMMETRIC_DEGREES),
               *RULE_PAIRS[0], *RULE_PAIRS[1], CORNER_MIDDLE_RULE,
               *(SYMMETRIC_RULES[d] for d in tol.AREA_SMALL_SYMMETRIC_DEGREES),
               *((np.concatenate([SYMMETRIC_RULES[d][0] for d in tol.AREA_SYMMETRIC_DEGREES]),
                  w) for w in SYMMETRIC_NULL_RULES))
#: The tolerances the compiled levels read, by name (read at each call).
LEVEL_TOLERANCES = (
    "AREA_IMAGE_ULPS", "AREA_SLIVER_ULPS", "AREA_MAX_PIECES", "AREA_IMAGE_PRECISE_RTOL", "C1",
    "C2", "EPS", "AREA_SLIVER_SHARE", "AREA_IMAGE_BUDGET_SHARE", "AREA_BACK_FACE_RTOL",
    "AREA_EDGE_ON_RTOL", "AREA_IMAGE_PRECISE_SHARE", "AREA_BOOLEAN_ULPS", "AREA_IMAGE_RTOL",
    "OFFSET_ROUNDING_ULPS", "AREA_SMALL_TRIANGLE_SHARE",
    "AREA_SMALL_TRIANGLE_REACH", "AREA_NULL_RULE_FACTOR", "AREA_MAX_DEPTH",
    "AREA_POINTS_PER_CALL")

#: The tolerances the compiled pair reads, by name (``_core/occluded_pair.h``).
PAIR_TOLERANCES = (
    "AREA_HIDDEN_PAD", "AREA_RAY_PARALLEL", "AREA_EVENT_PARALLEL", "AREA_EVENT_LINE_ULPS",
    "AREA_HULL_RTOL",
    "AREA_CUT_EXTEND_RTOL", "AREA_CURVED_EVENT_RTOL", "AREA_CURVED_CHORD_SPLIT",
    "AREA_EVENT_LINE_KEY", "AREA_SLIVER_CELL", "AREA_CELL_COVER_RTOL", "AREA_CELL_COVER_ATOL_SHARE",
    "AREA_LOW_RULES_TOLERANCE", "BSP_COPLANAR_ULPS", "EPS", "AREA_CURVED_EVENT_SAMPLES",
    "AREA_CURVED_EVENT_BISECTIONS", "AREA_CURVED_MAX_TRIPLES", "AREA_CURVED_CHORD_HALVINGS",
    "AREA_EVENT_ROWS_PER_CALL", "AREA_UMBRA_MIN_LINES", "AREA_MAX_EVENT_LINES",
    "AREA_MANY_CELLS", "CONVEX_TURN_ULPS", "CLIP_MEET_ULPS", "AREA_STRICT_TURN",
    "AREA_BOUND_COS_SLACK", "AREA_BOUND_SPREAD_ULPS", "AREA_UNEVALUATED_SHARE",
    "AREA_UNEVALUATED_LEAST")
_pair_constants_cache = {}
#: The tolerances' values read at each call (one lookup of them all, in the module's
#: namespace: the call is made once a pair).
_TOLERANCE_VALUES = operator.itemgetter(*(PAIR_TOLERANCES + LEVEL_TOLERANCES))


def blas_fuses():
    """Whether numpy's products of float arrays fuse their multiply-adds (as x86-64
    OpenBLAS's kernels may: ``fma(a2, b2, fma(a1, b1, a0 b0))``), for a vector's dot, a
    (k, 3) @ (3, m) product and a (t, 3, 2) @ (2, 3) one: the compiled pair rounds as
    they do (``_core/numpy_ops.h``, which says what it does not imitate). Each probe has
    ``a1 b1`` inexact and ``a0 b0 = -1``: fused, the result keeps the product's rounding
    error (2**-60).

    Examples
    --------
    >>> len(blas_fuses()), all(isinstance(f, bool) for f in blas_fuses())
    (3, True)
    """
    e = 1.0 + 2.0 ** -30
    fused = 2.0 ** -29 + 2.0 ** -60
    a, b = np.array([1.0, e, 0.0]), np.array([-1.0, e, 0.0])
    A = np.array([[1.0, e, 0.0]] * 4)
    T = np.array([[[1.0, e]] * 3] * 2)
    R = np.array([[-1.0, 0.0, 0.0], [e, 0.0, 0.0]])
    return (float(a @ b) == fused, float((A @ np.stack([b, b]).T)[0, 0]) == fused,
            float((T @ R)[0, 0, 0]) == fused)


def pair_constants():
    """The compiled pair's tolerances and rules (:func:`exactff.area._pair.pair_constants`),
    built again only where a tolerance changed since the last call.

    Examples
    --------
    >>> pair_constants() is pair_constants()          # kept while no tolerance changes
    True
    """
    values = _TOLERANCE_VALUES(vars(tol)) + (NORMAL_FLOOR,)
    # the tolerances and their constants stored as one entry: rows in threads read them
    # while another stores them (two entries, one stored before the other, let a thread
    # read the new tolerances with the old constants, or with none yet)
    cached = _pair_constants_cache.get("entry")
    if cached is None or cached[0] != values:
        names = PAIR_TOLERANCES + LEVEL_TOLERANCES
        cached = (values, _compiled_pair_constants(
            dict(zip(names, values)) | {"NORMAL_FLOOR": NORMAL_FLOOR}, LEVEL_RULES,
            _BLAS_FUSES))
        _pair_constants_cache["entry"] = cached
    return cached[1]


def hidden_integral_in_one_call(S, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid,
                                inner):
    """:func:`~exactff.area.adaptive._hidden_integral` in one compiled call
    (``_core/occluded_pair.cpp``, the GIL released): the same steps, numpy's roundings
    kept (the values are the reference's to the bit). Returns ``(0, value, err, points,
    culled_events, solid_events, curved_events, curved_skipped, back_faces,
    unevaluated)``, or
    ``(status,)`` with status > 0 where it declines the pair for the reference's steps
    (an umbra to look for, too many distinct lines, GEOS's cells, a blocker in the
    receiver's plane with solids, no compiled hidden set-up or levels, the rules' sum to
    check triangle by triangle).

    Examples
    --------
    Two unit squares 2 apart, a 0.5 x 0.5 plate halfway between (the unoccluded value
    ``whole`` by the closed form, per unit area of P):

    >>> import exactff as ef
    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> Q = P[::-1] + [0, 0, 2]
    >>> plate = np.array([[.25, .75, 1], [.75, .75, 1], [.75, .25, 1], [.25, .25, 1]])
    >>> whole = (ef.polygon_form_factor(P, Q), 0.0)
    >>> r = hidden_integral_in_one_call([Q, plate], P, Q, np.array([0, 0, 1.0]), 1e-8,
    ...                                 1.0, whole, True, None, None)
    >>> r[0], round(r[1], 8), bool(r[2] <= 1e-8)
    (0, 0.03140269, True)
    """
    W = np.concatenate(S)
    start = np.array([0, *itertools.accumulate(map(len, S))], dtype=np.int64)
    with_solids = solid is not None
    return _compiled_occluded_pair(
        W, start, solid if with_solids else _NO_SOLID,
        inner if with_solids and inner is not None else _NO_INNER, Pc, Qc, nP, atol, area_P,
        whole[0], whole[1], shortcuts, pair_constants())


_BLAS_FUSES = blas_fuses()
_NO_SOLID = np.zeros(0, dtype=np.int64)
_NO_INNER = np.zeros((0, 3))
