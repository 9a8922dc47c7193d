"""Setting the fields of a frozen dataclass after validation.

A frozen dataclass (``@dataclass(frozen=True)``) that normalises its inputs in
``__post_init__`` (arrays made read-only, sequences made tuples, values converted to their
units) must store the normalised values through ``object.__setattr__``, since its own
``__setattr__`` refuses. :func:`set_fields` does that for any number of fields in one call,
so a class states its normalised fields once, by name; :func:`readonly` is the read-only
array such a field holds.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

__all__ = ["readonly", "set_fields"]


def set_fields(obj: object, **fields: object) -> None:
    """Store ``fields`` (name = value) on ``obj``, bypassing a frozen dataclass's refusal.

    For use in ``__post_init__`` (or a constructor returning a modified copy) only: the
    instance must not have been handed out yet, since frozen instances are assumed immutable
    (hashing, caches).

    Parameters
    ----------
    obj : object
        The frozen dataclass instance (slots or not).
    **fields : object
        Attribute name and its value, set in the order given.
    """
    for name, value in fields.items():
        object.__setattr__(obj, name, value)


def readonly(a: npt.ArrayLike, dtype: npt.DTypeLike = float) -> np.ndarray:
    """A read-only copy of ``a`` as ``dtype``, for a frozen instance's array field.

    A copy, so that the caller's array stays writable and later changes to it do not reach
    the instance. numpy is imported here, not with the module, which the wire-format
    modules import without needing numpy.

    Parameters
    ----------
    a : array_like
        The values, any shape.
    dtype : data-type
        The array's type (default float).

    Returns
    -------
    numpy.ndarray
        Same shape as ``a``, ``flags.writeable`` False.
    """
    import numpy as np

    arr = np.array(a, dtype=dtype)
    arr.setflags(write=False)
    return arr
