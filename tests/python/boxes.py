# kdmesh — shared fixtures of the Python client tests: two unit boxes and a tet volume.
# SPDX-License-Identifier: AGPL-3.0-or-later
import numpy as np


def two_boxes():
    """Two disjoint unit boxes (two regions), the second at x in [2, 3]."""
    v = np.array([[(i & 1), (i >> 1 & 1), (i >> 2 & 1)] for i in range(8)], dtype=float)
    f = np.array([0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                  2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5]).reshape(-1, 3)
    return np.vstack([v, v + [2.0, 0.0, 0.0]]), np.vstack([f, f + 8])


def volume(points, tets):
    """The summed signed volume of linear tets (rows of 4 point ids)."""
    p = points[tets]
    return np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])).sum() / 6
