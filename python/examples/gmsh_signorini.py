# %% [markdown]
# # A Signorini problem on a gmsh mesh
#
# A notebook-style script (cells marked `# %%`, run it top to bottom or open it in Jupyter
# with jupytext): the mesh is built with the **gmsh Python API**, handed to gradvi as arrays,
# and the contact zone is plotted with **matplotlib**.
#
# The problem, on the strip Ω = (0, 2) × (0, 1) with a stiffer circular inclusion:
#
# * −div(A∇u) = f = 10 sin(πx): the source pushes up on the left half, pulls down on the right;
# * A = I, and A = 10 I in the disc of radius 0.2 around (0.5, 0.5);
# * u = 0 on the top (Γ1), A∇u·n = 0 on the sides (Γ2);
# * on the bottom Γ3, the Signorini condition u ≤ 0, A∇u·n ≤ 0, u A∇u·n = 0.
#
# Where the source pushes up, the bottom touches the barrier u = 0: that is the contact zone.

# %%
import sys
from pathlib import Path

import gmsh
import matplotlib

matplotlib.use("Agg")  # no display needed: the figure goes to a PNG file
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection, PolyCollection

import gradvi

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path.cwd()

# %% [markdown]
# ## The mesh, with gmsh
# A rectangle with the circle of the inclusion embedded, so that the interface is a mesh line.
# Boundary curves get physical tags: 1 top, 2 sides, 3 bottom.

# %%
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("strip")
occ = gmsh.model.occ
rect = occ.addRectangle(0, 0, 0, 2, 1)
disc = occ.addDisk(0.5, 0.5, 0, 0.2, 0.2)
occ.fragment([(2, rect)], [(2, disc)])
occ.synchronize()
tags = {1: [], 2: [], 3: []}
for dim, curve in gmsh.model.getEntities(1):
    x, y, _ = occ.getCenterOfMass(dim, curve)
    if abs(y - 1) < 1e-9:
        tags[1].append(curve)
    elif abs(y) < 1e-9:
        tags[3].append(curve)
    elif abs(x) < 1e-9 or abs(x - 2) < 1e-9:
        tags[2].append(curve)
for tag, curves in tags.items():
    gmsh.model.addPhysicalGroup(1, curves, tag)
gmsh.model.addPhysicalGroup(2, [s for _, s in gmsh.model.getEntities(2)], 10)
gmsh.option.setNumber("Mesh.MeshSizeMax", 0.04)
gmsh.model.mesh.generate(2)

# %% [markdown]
# From gmsh's arrays to a `gradvi.Mesh`: node coordinates, triangles (element type 2) and the
# boundary lines (type 1) of each physical group, as `{tag: [(a, b), ...]}`. (Writing a `.msh`
# file and calling `gradvi.Mesh.read`, or going through `meshio`, gives the same mesh.)

# %%
node_tags, coords, _ = gmsh.model.mesh.getNodes()
index = np.zeros(int(node_tags.max()) + 1, dtype=np.int64)
index[node_tags.astype(np.int64)] = np.arange(len(node_tags))
points = coords.reshape(-1, 3)[:, :2]
_, _, tri_nodes = gmsh.model.mesh.getElements(2)
triangles = index[tri_nodes[0].astype(np.int64)].reshape(-1, 3)
boundary_tags = {}
for tag, curves in tags.items():
    pairs = []
    for curve in curves:
        _, _, line_nodes = gmsh.model.mesh.getElements(1, curve)
        pairs.append(index[line_nodes[0].astype(np.int64)].reshape(-1, 2))
    boundary_tags[tag] = np.concatenate(pairs)
gmsh.finalize()

mesh = gradvi.Mesh(points, triangles, boundary_tags=boundary_tags)
print(mesh)

# %% [markdown]
# ## The problem, from Python
# Every datum is a vectorised callable: gradvi calls it once, on the arrays of the points where
# the scheme needs it. The boundary parts are selected by their gmsh tags.

# %%
def diffusion(x, y):
    inside = (x - 0.5) ** 2 + (y - 0.5) ** 2 < 0.2**2
    return np.where(inside, 10.0, 1.0)  # isotropic: A = a(x) I


problem = gradvi.Problem(
    source=lambda x, y: 10 * np.sin(np.pi * x),
    diffusion=diffusion,
    boundary={"dirichlet": 1, "neumann": 2, "signorini": 3},
    signorini=0.0,
    side="upper",  # u <= 0 on the bottom
    name="signorini-inclusion",
)

# %% [markdown]
# ## Solve with HMM and P1
# Both solutions are certified; the contact zone is where the Signorini unknowns are active.

# %%
solutions = {scheme: gradvi.solve(mesh, problem, scheme=scheme) for scheme in ("hmm", "p1")}
for scheme, sol in solutions.items():
    x_active = sol.constrained_points[sol.active, 0]
    print(
        f"{scheme}: NITER {sol.niter}, {sol.n_active} active unknowns on Γ3, contact length "
        f"{sol.contact_measure:.4f}, contact zone x in [{x_active.min():.3f}, {x_active.max():.3f}], "
        f"certificate {sol.certificate.worst():.1e}"
    )

# %% [markdown]
# ## The contact zone
# Left: Π_D u of the HMM solution, with the active edges of Γ3 in red. Right: the trace of u on
# Γ3 and the contact pressure λ_j / m_j (multiplier over the measure of the unknown).

# %%
hmm = solutions["hmm"]
fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.2), gridspec_kw={"width_ratios": [1.6, 1]})
polys = PolyCollection([mesh.points[c] for c in mesh.cells], array=hmm.u_cell, cmap="viridis", edgecolors="face")
ax.add_collection(polys)
fig.colorbar(polys, ax=ax, label="u")
active_edges = np.nonzero(hmm.active_edges)[0]
ax.add_collection(LineCollection(mesh.points[mesh.edges[active_edges]], colors="red", linewidths=4, label="contact (active)"))
ax.set(xlim=(0, 2), ylim=(-0.05, 1), aspect="equal", title="HMM: u and the contact zone on Γ3")
ax.legend(loc="upper right")
for scheme, sol in solutions.items():
    x = sol.constrained_points[:, 0]
    order = np.argsort(x)
    bx.plot(x[order], sol.u[sol.constrained_dofs][order], label=f"u on Γ3 ({scheme})")
    pressure = sol.multiplier / sol.constrained_measures
    bx.plot(x[order], pressure[order], "--", label=f"λ / m ({scheme})")
bx.axhline(0, color="k", lw=0.5)
bx.set(xlabel="x", title="trace and multiplier on Γ3")
bx.legend()
fig.tight_layout()
png = out / "gmsh_signorini.png"
fig.savefig(png, dpi=110)
print(f"wrote {png}")
