# %% [markdown]
# # A 3D Signorini problem on a gmsh mesh
#
# A notebook-style script (cells marked `# %%`: run it top to bottom, or open it in Jupyter
# with jupytext). The tetrahedral mesh is built with the **gmsh Python API**, gradvi solves
# the problem with HMM, and **matplotlib** draws the contact zone on the contact face.
#
# The problem, on the slab Ω = (0, 2) × (0, 1) × (0, 1) with a stiffer ball inside:
#
# * −div(A∇u) = f = 10 sin(πx): the source pushes up on the left half, pulls down on the right;
# * A = I, and A = 10 I in the ball of radius 0.25 around (0.5, 0.5, 0.5) (A_K = A(x_K));
# * u = 0 on the top z = 1 (Γ1), A∇u·n = 0 on the four sides (Γ2);
# * on the bottom z = 0 (Γ3), the Signorini condition u ≤ 0, A∇u·n ≤ 0, u A∇u·n = 0.
#
# Where the source pushes up, the bottom touches the barrier u = 0: that is the contact zone,
# a part of the bottom face.
#
# Usage: `python signorini3d.py [figure.png]` (default: `signorini3d.png` in a new temporary
# directory; the path is printed). Needs `gmsh` and `matplotlib` (`pip install gmsh
# matplotlib`); without them the script says so and stops.

# %%
import sys
import tempfile
from pathlib import Path

import numpy as np

import gradvi

try:
    import gmsh
    import matplotlib

    matplotlib.use("Agg")  # no display needed: the figure goes to a PNG file
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
except ImportError as e:
    sys.exit(
        f"this example needs the gmsh and matplotlib Python packages ({e}); install them with "
        "`pip install gmsh matplotlib` (`make python-examples` does)"
    )

if len(sys.argv) > 1:
    png = Path(sys.argv[1])
else:
    png = Path(tempfile.mkdtemp(prefix="gradvi-signorini3d-")) / "signorini3d.png"

# %% [markdown]
# ## The mesh, with gmsh
# A box with the ball of the inclusion embedded (so that its surface is made of mesh faces).
# Boundary surfaces get physical tags: 1 top, 2 sides, 3 bottom. gmsh writes a `.msh` file
# (format 4.1, ASCII) in a temporary directory (removed once read), and `gradvi.Mesh3.read`
# reads it with the physical surfaces as face tags.

# %%
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("slab")
occ = gmsh.model.occ
box = occ.addBox(0, 0, 0, 2, 1, 1)
ball = occ.addSphere(0.5, 0.5, 0.5, 0.25)
occ.fragment([(3, box)], [(3, ball)])
occ.synchronize()
tags = {1: [], 2: [], 3: []}
for dim, surface in gmsh.model.getEntities(2):
    x, y, z = occ.getCenterOfMass(dim, surface)
    if abs(z - 1) < 1e-9:
        tags[1].append(surface)
    elif abs(z) < 1e-9:
        tags[3].append(surface)
    elif min(abs(x), abs(x - 2), abs(y), abs(y - 1)) < 1e-9:
        tags[2].append(surface)
for tag, surfaces in tags.items():
    gmsh.model.addPhysicalGroup(2, surfaces, tag)
gmsh.model.addPhysicalGroup(3, [v for _, v in gmsh.model.getEntities(3)], 10)
gmsh.option.setNumber("Mesh.MeshSizeMax", 0.1)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.option.setNumber("Mesh.Binary", 0)
gmsh.model.mesh.generate(3)
with tempfile.TemporaryDirectory(prefix="gradvi-") as tmp:
    msh = Path(tmp) / "slab.msh"
    gmsh.write(str(msh))
    gmsh.finalize()
    mesh = gradvi.Mesh3.read(msh)
print(mesh)

# %% [markdown]
# ## The problem, from Python
# On a 3D mesh every callable takes (x, y, z) numpy arrays; gradvi calls each once, on the
# points where the scheme needs it. The boundary parts are selected by their gmsh tags.

# %%
def diffusion(x, y, z):
    inside = (x - 0.5) ** 2 + (y - 0.5) ** 2 + (z - 0.5) ** 2 < 0.25**2
    return np.where(inside, 10.0, 1.0)  # isotropic: A = a(x) I


problem = gradvi.Problem(
    source=lambda x, y, z: 10 * np.sin(np.pi * x),
    diffusion=diffusion,
    boundary={"dirichlet": 1, "neumann": 2, "signorini": 3},
    signorini=0.0,
    side="upper",  # u <= 0 on the bottom
    name="signorini-3d-inclusion",
)

# %% [markdown]
# ## Solve with HMM
# The solution is certified; the contact zone is where the Signorini unknowns (one per face
# of Γ3, at its centroid) are active.

# %%
sol = gradvi.solve(mesh, problem, scheme="hmm")
x_active = sol.constrained_points[sol.active, 0]
print(
    f"hmm: NITER {sol.niter}, {sol.n_unknowns} unknowns, {sol.n_active} of {sol.active.size} "
    f"faces of Γ3 in contact, contact area {sol.contact_measure:.4f} (of 2), contact zone x in "
    f"[{x_active.min():.3f}, {x_active.max():.3f}], certificate {sol.certificate.worst():.1e}"
)

# %% [markdown]
# ## The contact zone on the bottom face
# Left: the faces of Γ3 seen from below, coloured by the contact pressure λ_j / |σ_j|
# (multiplier over the face area; zero off contact), the contact faces outlined. Right: the
# trace of u on Γ3 against x (u = 0 on the contact zone, u < 0 off it).

# %%
faces = sol.dof_index[sol.constrained_dofs]  # the face of each Signorini unknown
off, conn = mesh.face_offsets, mesh.face_connectivity
polygons = [mesh.points[conn[off[f] : off[f + 1]], :2] for f in faces]
pressure = sol.multiplier / sol.constrained_measures
fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.2), gridspec_kw={"width_ratios": [1.6, 1]})
coll = PolyCollection(polygons, array=pressure, cmap="magma", edgecolors="face")
ax.add_collection(coll)
fig.colorbar(coll, ax=ax, label="contact pressure λ / |σ|")
ax.add_collection(
    PolyCollection([p for p, a in zip(polygons, sol.active) if a], facecolors="none", edgecolors="cyan", linewidths=0.4)
)
ax.set(xlim=(0, 2), ylim=(0, 1), aspect="equal", xlabel="x", ylabel="y", title="HMM: the contact zone on Γ3 (z = 0)")
x = sol.constrained_points[:, 0]
bx.scatter(x[~sol.active], sol.u[sol.constrained_dofs][~sol.active], s=4, label="u on Γ3, free")
bx.scatter(x[sol.active], sol.u[sol.constrained_dofs][sol.active], s=4, c="red", label="u on Γ3, in contact")
bx.axhline(0, color="k", lw=0.5)
bx.set(xlabel="x", title="trace of u on Γ3")
bx.legend()
fig.tight_layout()
png.parent.mkdir(parents=True, exist_ok=True)
fig.savefig(png, dpi=110)
print(f"wrote {png}")
