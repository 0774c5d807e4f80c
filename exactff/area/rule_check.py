"""The check of an occluded pair's rules: the two rules' integrals of the unoccluded
point values U over the emitter's triangles must add up, within their differences, to
the pair's closed form; where they do not, each triangle is checked against its own
closed form, and those its check shows to err more than their differences (or, while
the sum still misses, whose check cannot tell) are refined (docs/explanation/area-form-factors.md, "The rules'
check").
"""

import numpy as np

from .. import _tolerances as tol
from ..geometry import area_vector, cross
from .closed_form import unoccluded_pairs
from .rules import triangle_areas

__all__ = ["triangle_unoccluded", "missed_unoccluded", "checked_rules"]


def triangle_unoccluded(T, nP, Qc, atol=np.inf):
    """``int_T F(x -> Qc) dA_x`` for each triangle T (t, 3, 3) in the plane of normal nP,
    unoccluded (Qc wholly in front of that plane, each T in front of Qc's), and its
    rounding estimate: by reciprocity ``A_Qc F(Qc -> T)``, the closed form
    (:func:`~exactff.area.closed_form.unoccluded_pairs`); where its terms cancel, its
    estimate says so, and where that misses ``atol`` (the default: never) its fallbacks
    take over (the contour rule, then mpmath).

    Examples
    --------
    A unit square's two triangles against the square 1 above (Howell's C-11: the
    whole square's 0.19982489570, their sum):

    >>> Q = np.array([[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]], float)
    >>> T = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 0, 0], [1, 1, 0], [0, 1, 0]]],
    ...              float)
    >>> U, E = triangle_unoccluded(T, np.array([0.0, 0.0, 1.0]), Q)
    >>> round(float(U.sum()), 11), bool(np.all(E < 1e-13))
    (0.1998248957, True)
    """
    if not len(T):
        return np.zeros(0), np.zeros(0)
    # counter-clockwise seen from nP's side
    flip = np.einsum("tx,x->t", cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), nP) < 0
    T = np.where(flip[:, None, None], T[:, ::-1], T)
    area_Q = float(np.linalg.norm(area_vector(Qc)))
    f, e = unoccluded_pairs(Qc, list(T), shortcuts=False, atol=atol / area_Q,
                            parts=[(Qc, t) for t in T])
    return area_Q * f, area_Q * e


def missed_unoccluded(cat, whole, lost):
    """How far the rules' integrals of U over the triangles ``cat`` (per unit area of
    P: ``hiU``, ``loU``, ``hi``, ``lo``, ``diff``, ``rndU``) miss the pair's closed form
    ``whole`` (value, estimate) beyond what their differences allow, ``lost`` (the
    emitter's area not integrated, per unit area) aside: at most 0 where the
    differences bound the rules' errors on H and on ``U - H``. Returns that excess and
    the differences on ``U - H`` per triangle."""
    dF = np.abs((cat["hiU"] - cat["loU"]) - (cat["hi"] - cat["lo"]))
    missed = (abs(float(cat["hiU"].sum()) - whole[0]) - float((cat["diff"] + dF).sum())
              - float(cat["rndU"].sum()) - whole[1] - lost)
    return missed, dF


def checked_rules(Ta, cat, todo, missed, dF, nP, Qc, area_P, atol, total_area):
    """Each triangle ``Ta[todo]`` checked against its own closed form
    (:func:`triangle_unoccluded`, to the least of their limits below): its rules' difference ``cat["diff"]`` raised to the
    error its check shows on U (beyond its difference on ``U - H``, ``dF``, and the
    estimates); refined where that exceeds ``AREA_RULE_CHECK_SHARE`` of its share of
    ``atol`` (half of it, by area of ``total_area``), and, where the differences so
    raised still leave part of ``missed`` (:func:`missed_unoccluded`) unexplained, also
    where the check cannot tell (its closed form's estimate is above that share). Not
    those at the last level (rung 1 at ``AREA_MAX_DEPTH``). Updates ``cat["diff"]`` and
    ``cat["checked"]``; returns the triangles to refine (a bool mask over ``Ta``)."""
    limit = tol.AREA_RULE_CHECK_SHARE * 0.5 * atol / total_area * triangle_areas(Ta[todo])
    exU, exE = triangle_unoccluded(Ta[todo], nP, Qc, float(limit.min()) * area_P)
    shown = np.abs(cat["hiU"][todo] - exU / area_P) - dF[todo] - cat["rndU"][todo] - exE / area_P
    raised = np.maximum(cat["diff"][todo], shown)
    left = missed - float((raised - cat["diff"][todo]).sum())
    cat["diff"][todo] = raised
    cat["checked"][todo] = True
    again = np.zeros(len(Ta), dtype=bool)
    again[todo] = (shown > limit) | ((left > 0) & ~(exE / area_P <= limit))
    last = (cat["rung"].astype(int) == 1) & (cat["depth"].astype(int) >= tol.AREA_MAX_DEPTH)
    return again & ~last
