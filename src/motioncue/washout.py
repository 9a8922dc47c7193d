"""Former name of :mod:`motioncue.cueing`, kept so existing scripts keep working.

The stage was renamed when it stopped being one washout filter: it is the cueing stage, with
the classical washout as one algorithm among others. Import from :mod:`motioncue.cueing`.
"""

import warnings

from motioncue.cueing import *  # noqa: F403
from motioncue.cueing import __all__  # noqa: F401

warnings.warn(
    "motioncue.washout was renamed motioncue.cueing; import from motioncue.cueing",
    DeprecationWarning,
    stacklevel=2,
)
