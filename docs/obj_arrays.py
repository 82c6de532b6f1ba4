"""A model's vertices and triangles as numpy arrays, for the docs' scripts that build scenes in memory."""
import numpy as np


def load_obj(path, height=None):
    """The OBJ's 'v' and 'f' lines (polygons as fans, negative indices counted from the end); with
    `height`, scaled to that height and stood on y = 0 about x = z = 0."""
    vertices, triangles = [], []
    with open(path) as obj:
        for line in obj:
            if line.startswith("v "):
                vertices.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                corners = [int(corner.split("/")[0]) for corner in line.split()[1:]]
                corners = [c - 1 if c > 0 else len(vertices) + c for c in corners]
                triangles += [[corners[0], corners[k], corners[k + 1]] for k in range(1, len(corners) - 1)]
    vertices = np.array(vertices)
    if height is not None:
        low, high = vertices.min(axis=0), vertices.max(axis=0)
        vertices = (vertices - [(low[0] + high[0]) / 2, low[1], (low[2] + high[2]) / 2]) * (height / (high[1] - low[1]))
    return vertices, np.array(triangles)


def room(half_width, height):
    """Four walls and a ceiling about x = z = 0, from y = 0 (a floor plane goes below them)."""
    corners = np.array([[x, y, z] for x in (-half_width, half_width) for y in (0.0, height) for z in (-half_width, half_width)])
    triangles = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 2, 6], [0, 6, 4], [2, 3, 7], [2, 7, 6],
                          [1, 5, 7], [1, 7, 3]])
    return corners, triangles
