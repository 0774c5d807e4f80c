"""Per-scene accelerators, built once and kept beside the scene, not in it.

A :class:`exactff.Scene` holds data only. What the engines derive from it (the flat
polygon arrays, the BSP tree, the convexity flag, the padded buckets) is built on first
use and kept in one :class:`Prepared` object per scene, held in a weak dictionary: it
goes with the scene, is shared by the threads of a process (under a lock), and is not
pickled with the scene (a worker builds its own).
"""

import threading
import weakref

__all__ = ["Prepared", "prepared"]

_PREPARED = weakref.WeakKeyDictionary()
_LOCK = threading.RLock()


class Prepared:
    """The accelerators of one scene, by name.

    Examples
    --------
    >>> import exactff as ef
    >>> s = ef.scenes.subdivided_box(1)
    >>> prepared(s).get("count", lambda scene: len(scene))
    6
    >>> prepared(s) is prepared(s)
    True
    """

    __slots__ = ("_scene", "_values", "_lock")

    def __init__(self, scene):
        self._scene = weakref.ref(scene)
        self._values = {}
        self._lock = threading.RLock()   # this scene's builds only (re-entrant: one may need another)

    def get(self, name, build):
        """The accelerator ``name``, built as ``build(scene)`` on first use."""
        value = self._values.get(name)
        if value is not None:
            return value      # built: no lock on the hot path
        with self._lock:
            if name not in self._values:
                self._values[name] = build(self._scene())
            return self._values[name]

    def put(self, name, value):
        """Set the accelerator ``name`` (a test's own BSP tree, say)."""
        with self._lock:
            self._values[name] = value

    def __contains__(self, name):
        return name in self._values


def prepared(scene):
    """The :class:`Prepared` accelerators of ``scene`` (created on first use)."""
    with _LOCK:
        p = _PREPARED.get(scene)
        if p is None:
            p = _PREPARED[scene] = Prepared(scene)
        return p
