"""Figure output shared by every picture the package writes: matplotlib on its file-only Agg backend, PNG images
and figures written atomically (a failed or interrupted write leaves no partial file).
"""
from __future__ import annotations

import numpy as np

from .files import atomic_path

__all__ = ["pyplot", "save_png", "save_figure"]


def pyplot():
    """``matplotlib.pyplot`` on the Agg backend (files only, no display needed): the one place that chooses it."""
    # deferred: matplotlib takes a fifth of a second to import and only figure writers need it
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # after the backend is chosen

    return plt


def save_png(path, image, *, overwrite=True):
    """Write an (h, w, 3) display image in [0, 1] as PNG atomically."""
    with atomic_path(path, overwrite=overwrite) as tmp:
        pyplot().imsave(str(tmp), np.clip(image, 0, 1), format="png")


def save_figure(fig, path, *, overwrite=True, dpi=110):
    """Save a matplotlib figure as PNG atomically and close it."""
    with atomic_path(path, overwrite=overwrite) as tmp:
        fig.savefig(str(tmp), format="png", dpi=dpi, bbox_inches="tight")
    pyplot().close(fig)
