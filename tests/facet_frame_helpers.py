"""Helper shared by the facet-frame tests: the facet-frame sum of the library at exactly one direction pair."""
import numpy as np

from waveoptics.brdf import facet_frame_diffraction
from waveoptics.scatter.grid import DirectionGrid


def facet_frame_at(a, c, lam, mat, micro, nano, table):
    """The diffracted part (1/sr) at incidence *a* and exit *c*: the pair turned so that *a* lies at azimuth 0, *c*
    the one direction of a cell of width 2e-7, read from facet tables on *table*."""
    p = np.arctan2(a[1], a[0])
    rot = np.array([[np.cos(p), np.sin(p), 0.0], [-np.sin(p), np.cos(p), 0.0], [0.0, 0.0, 1.0]])
    a, c = rot @ a, rot @ c
    cell = DirectionGrid(1, 1, (c[0] - 1e-7, c[0] + 1e-7), (c[1] - 1e-7, c[1] + 1e-7))
    d, _, _ = facet_frame_diffraction(a, [lam], mat, micro, nano, cell, lambda x, w: mat.F(x, w), table_grid=table)
    return d[0, 0, 0]
