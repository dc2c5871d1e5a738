"""The oblique phantom of the direction-matrix tests: a sphere field off the grid's centre and
origin (a rotation about the wrong point, or a missing one, moves it by several voxels)."""

import numpy as np

#: world centre and radius of the phantom sphere
CENTRE = np.array([12.0, -4.0, 9.0])
RADIUS = 6.0


def rotation(ax, ay, az):
    """A rotation by ``ax``, ``ay``, ``az`` degrees about x, then y, then z: (3, 3)."""
    a, b, c = np.radians([ax, ay, az])
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx
