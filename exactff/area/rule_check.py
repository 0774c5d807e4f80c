"""The check of an occluded pair's rules: the two rules' integrals of the unoccluded
point values U over the emitter's triangles must add up, within their differences, to
the pair's closed form; where they do not, each triangle is checked against its own
closed form, and those its check shows to err more than their differences (or, while
the sum still misses, whose check cannot tell) are refined
(docs/explanation/area-form-factors.md, "The rules' difference, checked").
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
    """How far the rules' integrals of U over the triangles miss the pair's closed form
    beyond what their differences allow: at most 0 where the differences bound the
    rules' errors on H and on ``U - H``.

    Parameters
    ----------
    cat : dict of ndarray of shape (t,)
        The triangles' rules, per unit area of P: ``hiU``, ``loU`` (the high and low
        rules' integrals of U), ``hi``, ``lo`` (of H), ``diff`` (the differences taken
        on H) and ``rndU`` (U's rounding).
    whole : (float, float)
        The pair's closed form (value, estimate), per unit area of P.
    lost : float
        The emitter's area not integrated, per unit area of P.

    Returns
    -------
    (float, ndarray of shape (t,))
        The excess, and each triangle's difference on ``U - H``.

    Examples
    --------
    Two triangles whose high rules sum to 0.3 against a closed form of 0.31 (within
    1e-12), with differences of 1e-3 each: 0.01 is missed, 0.008 beyond them:

    >>> z = np.zeros(2)
    >>> cat = {"hiU": np.array([0.1, 0.2]), "loU": np.array([0.1, 0.2]), "hi": z,
    ...        "lo": z, "diff": np.array([1e-3, 1e-3]), "rndU": z}
    >>> missed, dF = missed_unoccluded(cat, (0.31, 1e-12), 0.0)
    >>> round(missed, 9), dF.tolist()
    (0.008, [0.0, 0.0])
    """
    dF = np.abs((cat["hiU"] - cat["loU"]) - (cat["hi"] - cat["lo"]))
    missed = (abs(float(cat["hiU"].sum()) - whole[0]) - float((cat["diff"] + dF).sum())
              - float(cat["rndU"].sum()) - whole[1] - lost)
    return missed, dF


def checked_rules(Ta, cat, todo, missed, dF, nP, Qc, area_P, atol, total_area):
    """Each triangle ``Ta[todo]`` checked against its own closed form
    (:func:`triangle_unoccluded`, taken to the least of the triangles' limits): its
    rules' difference ``cat["diff"]`` raised to the error its check shows on U (beyond
    its difference on ``U - H`` and the estimates); refined where that exceeds
    ``AREA_RULE_CHECK_SHARE`` of its share of ``atol`` (half of it, by area of
    ``total_area``), and, while the differences so raised still leave part of ``missed``
    unexplained, also where the check cannot tell (its closed form's estimate is above
    that share). Not those at the last level (rung 1 at ``AREA_MAX_DEPTH``).

    Parameters
    ----------
    Ta : ndarray of shape (t, 3, 3)
        The emitter's triangles, in the plane of normal ``nP``.
    cat : dict of ndarray of shape (t,)
        Their rules (:func:`missed_unoccluded`'s, with ``checked``, ``rung`` and
        ``depth``); ``diff`` and ``checked`` are updated in place.
    todo : ndarray of int
        The triangles to check.
    missed : float
        :func:`missed_unoccluded`'s excess.
    dF : ndarray of shape (t,)
        The differences on ``U - H`` (:func:`missed_unoccluded`).
    nP, Qc : ndarray of shape (3,) and (m, 3)
        The emitter's normal and the receiver's part (wholly in front).
    area_P : float
        The emitter's area (the rules are per unit area of it).
    atol, total_area : float
        The pair's absolute tolerance and the area its budget spreads over.

    Returns
    -------
    ndarray of bool, shape (t,)
        The triangles to refine.

    Examples
    --------
    A unit square's two triangles under the square 1 above (their U exact: 0.19982489570
    in all), one of them off by 1e-3: only that one is refined:

    >>> Q = np.array([[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]], float)
    >>> T = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 0, 0], [1, 1, 0], [0, 1, 0]]],
    ...              float)
    >>> nP = np.array([0.0, 0.0, 1.0])
    >>> U = triangle_unoccluded(T, nP, Q)[0] + np.array([1e-3, 0.0])
    >>> z = np.zeros(2)
    >>> cat = {"hiU": U, "diff": z.copy(), "rndU": z, "checked": z.astype(bool),
    ...        "rung": np.ones(2), "depth": z}
    >>> checked_rules(T, cat, np.arange(2), 1e-3, z, nP, Q, 1.0, 1e-6, 1.0).tolist()
    [True, False]
    """
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
