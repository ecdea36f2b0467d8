"""Draw docs/images/boundary.png: the ghost-layer boundary rule on a small open mesh (top view)."""
from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from c1surf.evaluation.bezier import bernstein_basis, raise_degree  # noqa: E402
from c1surf.mesh.ghost_layer import add_ghost_layer, ghost_points_matrix, reflex_corners  # noqa: E402
from c1surf.mesh.repair import prepare_topology  # noqa: E402
from c1surf.evaluation.adjacency import match_patch_sides, side_polygons  # noqa: E402
from c1surf.construction.surface import Surface  # noqa: E402

# an L-shaped patch of quads with one triangle pair: straight runs, a reflex and convex corners
cells = [(i, j) for i in range(4) for j in range(3) if not (i >= 2 and j >= 2)]
index = {}
points = []
for i, j in cells:
    for p in [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]:
        if p not in index:
            index[p] = len(points)
            points.append((p[0], p[1], 0.0))
faces = [[index[(i, j)], index[(i + 1, j)], index[(i + 1, j + 1)], index[(i, j + 1)]] for i, j in cells]
points = np.array(points, float)
sizes = np.array([len(f) for f in faces])
vertices = np.concatenate(faces)
surface = Surface(sizes, vertices, points)

fig, ax = plt.subplots(figsize=(7, 5.5), dpi=110)
layer = add_ghost_layer(prepare_topology(sizes, vertices, len(points))[0])
ghost_points = ghost_points_matrix(layer, reflex_corners(layer, points)) @ points
mesh = layer.mesh
for f in range(mesh.n_faces):
    corner = mesh.origin[mesh.face_offsets[f]: mesh.face_offsets[f + 1]]
    poly = ghost_points[np.r_[corner, corner[:1]]]
    real = layer.real_face[f]
    ax.plot(poly[:, 0], poly[:, 1], "-" if real else "--", color="black" if real else "0.6", lw=1.6 if real else 1.0, zorder=2 if real else 1)
patches = np.concatenate([raise_degree(surface.biquadratic, 3, 3), surface.bicubic])
t = np.linspace(0, 1, 40)
basis = bernstein_basis(3, t)
for side in [patches[:, 0], patches[:, -1], patches[:, :, 0], patches[:, :, -1]]:
    for curve in np.einsum("mi,kid->kmd", basis, side):
        ax.plot(curve[:, 0], curve[:, 1], color="#4c9be8", lw=0.4, zorder=3)
sides = match_patch_sides([patches], 1e-9)
curves = np.stack(side_polygons(patches), axis=1)
lone = curves[np.divmod(sides.lone, 4)]
for curve in np.einsum("mi,kid->kmd", basis, lone):
    ax.plot(curve[:, 0], curve[:, 1], color="#d62728", lw=2.2, zorder=4)
ax.plot([], [], color="black", label="input mesh (open)")
ax.plot([], [], "--", color="0.6", label="ghost quads (a' = 2a - m(a))")
ax.plot([], [], color="#4c9be8", lw=0.8, label="patch edges")
ax.plot([], [], color="#d62728", lw=2.2, label="surface boundary")
ax.set_aspect("equal")
ax.axis("off")
ax.legend(loc="upper right", fontsize=8, frameon=False)
out = Path(__file__).resolve().parent / "images" / "boundary.png"
fig.savefig(out, bbox_inches="tight")
print(out)
