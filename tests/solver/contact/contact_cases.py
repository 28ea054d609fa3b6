"""Small two-body hexahedral meshes for the contact tests (built in memory with gmsh on rank 0).

Each mesh holds two disjoint bodies whose facing surfaces coincide geometrically but
do not share nodes, with different element counts on the two sides (non-matching).
Facet tags: ``MASTER`` and ``SLAVE`` for the contact surfaces.
"""

from mpi4py import MPI

import gmsh
import numpy as np

import dolfinx
from dolfinx.io import gmsh as gmshio

MASTER, SLAVE = 13, 14
LOWER, UPPER = 1, 2


def _to_mesh(
    comm: MPI.Comm, build
) -> tuple[dolfinx.mesh.Mesh, dolfinx.mesh.MeshTags, dolfinx.mesh.MeshTags]:
    """Run ``build`` (which fills the gmsh model) on rank 0 and distribute the mesh."""
    if comm.rank == 0:
        gmsh.initialize(interruptible=False)
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("contact_case")
        build()
    data = gmshio.model_to_mesh(gmsh.model if comm.rank == 0 else None, comm, 0, gdim=3)
    if comm.rank == 0:
        gmsh.finalize()
    return data.mesh, data.cell_tags, data.facet_tags


def _structured_box(x0, dx, n: tuple[int, int, int]) -> tuple[int, int, int]:
    """Hexahedral box by extrusion; returns (bottom surface, top surface, volume) tags."""
    occ = gmsh.model.occ
    rect = occ.addRectangle(x0[0], x0[1], x0[2], dx[0], dx[1])
    out = occ.extrude([(2, rect)], 0, 0, dx[2], numElements=[n[2]], recombine=True)
    occ.synchronize()
    for _, c in gmsh.model.getBoundary([(2, rect)], oriented=False):
        x = gmsh.model.occ.getCenterOfMass(1, c)
        along_x = abs(x[1] - x0[1]) < 1e-12 or abs(x[1] - x0[1] - dx[1]) < 1e-12
        gmsh.model.mesh.setTransfiniteCurve(c, (n[0] if along_x else n[1]) + 1)
    gmsh.model.mesh.setTransfiniteSurface(rect)
    gmsh.model.mesh.setRecombine(2, rect)
    return rect, out[0][1], out[1][1]


def two_blocks(
    comm: MPI.Comm,
    size: tuple[float, float] = (1.0, 1.0),
    heights: tuple[float, float] = (0.5, 0.5),
    lower: tuple[int, int, int] = (3, 3, 2),
    upper: tuple[int, int, int] = (4, 5, 2),
    order: int = 1,
    inset: float = 0.0,
):
    """A base [0,Lx]x[0,Ly]x[-H0,0] (LOWER, top face MASTER) and a block on it (UPPER, bottom SLAVE).

    The block covers [inset, Lx - inset] x [inset, Ly - inset] x [0, H1].
    """

    def build():
        b0, t0, v0 = _structured_box((0, 0, -heights[0]), (size[0], size[1], heights[0]), lower)
        b1, t1, v1 = _structured_box(
            (inset, inset, 0), (size[0] - 2 * inset, size[1] - 2 * inset, heights[1]), upper
        )
        gmsh.model.addPhysicalGroup(3, [v0], LOWER)
        gmsh.model.addPhysicalGroup(3, [v1], UPPER)
        gmsh.model.addPhysicalGroup(2, [t0], MASTER)
        gmsh.model.addPhysicalGroup(2, [b1], SLAVE)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(order)

    return _to_mesh(comm, build)


def _ring_sector(
    r0: float, r1: float, thickness: float, n_r: int, n_theta: int
) -> tuple[int, int, int]:
    """Quarter annulus r0 < r < r1, 0 < theta < pi/2, 0 < z < thickness; (inner, outer surface, volume)."""
    occ = gmsh.model.occ
    c = occ.addPoint(0, 0, 0)
    p = [
        occ.addPoint(r0, 0, 0),
        occ.addPoint(r1, 0, 0),
        occ.addPoint(0, r1, 0),
        occ.addPoint(0, r0, 0),
    ]
    lines = [
        occ.addLine(p[0], p[1]),
        occ.addCircleArc(p[1], c, p[2]),
        occ.addLine(p[2], p[3]),
        occ.addCircleArc(p[3], c, p[0]),
    ]
    surf = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    out = occ.extrude([(2, surf)], 0, 0, thickness, numElements=[1], recombine=True)
    occ.remove([(0, c)])
    occ.synchronize()
    for i, line in enumerate(lines):
        gmsh.model.mesh.setTransfiniteCurve(line, (n_r if i % 2 == 0 else n_theta) + 1)
    gmsh.model.mesh.setTransfiniteSurface(surf)
    gmsh.model.mesh.setRecombine(2, surf)
    volume = out[1][1]
    lateral = [tag for dim, tag in out[2:] if dim == 2]
    centres = {tag: gmsh.model.occ.getCenterOfMass(2, tag) for tag in lateral}
    arcs = sorted((np.hypot(x, y), tag) for tag, (x, y, _) in centres.items() if min(x, y) > 1e-9)
    return arcs[0][1], arcs[1][1], volume


def two_rings(
    comm: MPI.Comm,
    radii: tuple[float, float, float] = (0.5, 0.75, 1.0),
    interference: float = 1e-3,
    thickness: float = 0.05,
    inner: tuple[int, int] = (3, 10),
    outer: tuple[int, int] = (3, 7),
):
    """Quarter rings with radial interference (quadratic geometry).

    LOWER: inner ring a < r < b + interference, outer surface MASTER.
    UPPER: outer ring b < r < c, inner surface SLAVE. ``inner``/``outer`` = (n_r, n_theta).
    """
    a, b, c = radii

    def build():
        _, s0, v0 = _ring_sector(a, b + interference, thickness, *inner)
        s1, _, v1 = _ring_sector(b, c, thickness, *outer)
        gmsh.model.addPhysicalGroup(3, [v0], LOWER)
        gmsh.model.addPhysicalGroup(3, [v1], UPPER)
        gmsh.model.addPhysicalGroup(2, [s0], MASTER)
        gmsh.model.addPhysicalGroup(2, [s1], SLAVE)
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)

    return _to_mesh(comm, build)


def elastic_system(V, material, bcs, traction=None, facet_tags=None, traction_tag=None):
    """Bulk stiffness A (with bcs) and load b (lifted, bc values set) of linear elasticity.

    ``traction`` (a UFL vector [Pa]) acts on the facets tagged ``traction_tag``.
    """
    import ufl
    from petsc4py import PETSc

    import dolfinx.fem.petsc
    from solver.elasticity import epsilon, sigma

    mesh = V.mesh
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = dolfinx.fem.form(ufl.inner(sigma(u, material), epsilon(v)) * ufl.dx)
    zero = dolfinx.fem.Constant(mesh, np.zeros(3))
    L = ufl.inner(zero, v) * ufl.dx
    if traction is not None:
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
        L += ufl.inner(traction, v) * ds(traction_tag)
    L = dolfinx.fem.form(L)
    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=bcs)
    A.assemble()
    b = dolfinx.fem.petsc.assemble_vector(L)
    dolfinx.fem.petsc.apply_lifting(b, [a], [bcs])
    b.ghostUpdate(PETSc.InsertMode.ADD, PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(b, bcs)
    return A, b


def fixed(V, component: int, marker, value: float = 0.0):
    """Dirichlet condition u[component] = value [m] on the boundary facets selected by ``marker``."""
    from petsc4py import PETSc

    mesh = V.mesh
    facets = dolfinx.mesh.locate_entities_boundary(mesh, mesh.topology.dim - 1, marker)
    dofs = dolfinx.fem.locate_dofs_topological(V.sub(component), mesh.topology.dim - 1, facets)
    return dolfinx.fem.dirichletbc(PETSc.ScalarType(value), dofs, V.sub(component))


def gathered(comm: MPI.Comm, a):
    """Concatenation of a per-rank array over all ranks (for collective-safe assertions)."""
    return np.concatenate(comm.allgather(np.asarray(a)))


def sliding_block(
    comm: MPI.Comm,
    friction,
    steps: int,
    slide_per_step: float,
    dt: float | None,
    theta: int = 1,
    lagged: bool = False,
    rigid_base: bool = False,
    contact_type=None,
    drags=None,
    **newton,
):
    """Block (0.5 x 0.5 x 0.25 m) pressed on a clamped base by q = 1 MPa and dragged by its top face.

    The top face's x displacement grows by ``slide_per_step`` [m] per step (u_y = 0 there), or
    takes the values ``drags`` [m] (one per step; ``steps`` and ``slide_per_step`` unused),
    the rest of the top face is loaded by the pressure. The base is clamped on its bottom
    face, or with ``rigid_base`` at all its dofs (its top face, the master surface, then
    cannot move or rotate). ``contact_type`` (default NitscheContact) lets a test use a
    subclass of it with the same arguments. Returns (history, contact, solver results, u)
    with history rows (T / N, stick fraction, slip fraction) where T is the horizontal
    reaction of the top face (from the bulk stress) and N = q A the normal load.
    """
    import ufl
    from petsc4py import PETSc

    import dolfinx.fem.petsc
    from solver.contact import NitscheContact, Status
    from common.material import Material
    from solver.elasticity import epsilon, sigma
    from solver.dynamics.newton import ContactNewtonSolver

    H, q = 0.25, 1e6
    mesh, cell_tags, tags = two_blocks(
        comm, heights=(H, H), lower=(4, 4, 2), upper=(3, 3, 2), inset=0.25
    )
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (3,)))
    material = Material(E=1e9, nu=0.3)
    top = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], H))
    top_tags = dolfinx.mesh.meshtags(mesh, 2, top, np.full(len(top), 1, np.int32))
    drag = dolfinx.fem.Constant(mesh, 0.0)
    top_x = dolfinx.fem.locate_dofs_topological(V.sub(0), 2, top)
    bcs = [fixed(V, c, lambda x: np.isclose(x[2], -H)) for c in range(3)]
    bcs += [
        fixed(V, 1, lambda x: np.isclose(x[2], H)),
        dolfinx.fem.dirichletbc(drag, top_x, V.sub(0)),
    ]
    if rigid_base:
        base = dolfinx.fem.locate_dofs_topological(V, 3, cell_tags.find(LOWER))
        bcs.append(dolfinx.fem.dirichletbc(np.zeros(3), base, V))
    u_, v_ = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = dolfinx.fem.form(ufl.inner(sigma(u_, material), epsilon(v_)) * ufl.dx)
    load = dolfinx.fem.Constant(mesh, np.array([0.0, 0.0, -q]))
    L = dolfinx.fem.form(
        ufl.inner(load, v_) * ufl.Measure("ds", domain=mesh, subdomain_data=top_tags)(1)
    )
    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=bcs)
    A.assemble()
    u, u_old = dolfinx.fem.Function(V), dolfinx.fem.Function(V)
    reaction = dolfinx.fem.form(ufl.inner(sigma(u, material), epsilon(v_)) * ufl.dx)
    owned_x = top_x[top_x < V.dofmap.index_map.size_local * 3]
    contact = (contact_type or NitscheContact)(
        V, tags, SLAVE, MASTER, material, friction, gamma0=10.0, theta=theta, lagged_friction=lagged
    )
    solver = ContactNewtonSolver(A, bcs, **({"max_iterations": 40, "refactor_after": 0} | newton))
    N = q * 0.5 * 0.5
    history, results = [], []
    for value in slide_per_step * np.arange(1, steps + 1) if drags is None else drags:
        drag.value = value
        b = dolfinx.fem.petsc.assemble_vector(L)
        dolfinx.fem.petsc.apply_lifting(b, [a], [bcs])
        b.ghostUpdate(PETSc.InsertMode.ADD, PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(b, bcs)
        contact.set_reference(u_old, dt)
        results.append(solver.solve(b, contact, u))
        r = dolfinx.fem.petsc.assemble_vector(reaction)
        r.ghostUpdate(PETSc.InsertMode.ADD, PETSc.ScatterMode.REVERSE)
        T = comm.allreduce(r.array[owned_x].sum(), op=MPI.SUM)
        status = gathered(comm, contact.state.status)
        history.append((T / N, np.mean(status == Status.STICK), np.mean(status == Status.SLIP)))
        u_old.x.array[:] = u.x.array
    solver.destroy()
    return np.array(history), contact, results, u
