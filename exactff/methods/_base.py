"""The interface every form-factor method implements: one override, point rows."""

__all__ = ["FormFactorMethod"]


class FormFactorMethod:
    """Base class of the form-factor methods.

    A method implements :meth:`point_form_factors`; :func:`exactff.form_factors` and
    :func:`exactff.form_factor_matrix` do the broadcasting, the matrix rows and the
    parallel execution for every method alike.
    """

    #: name used by ``method="..."``
    name = None

    def point_form_factors(self, scene, point, normal, *, two_sided=False):
        """Form factors from one point (unit ``normal``) to every polygon: ``(N,)``."""
        raise NotImplementedError

    def __repr__(self):
        return f"{type(self).__name__}()"
